// Lightmap UV generation: the data that flows between its three stages.
//
//   segment + parametrize (charts.h)   mesh -> charts flattened to the plane
//   pack (bitimage_packer.h)           charts -> places in one atlas
//   assemble (generate.h)              placed charts -> TEXCOORD_1 per vertex,
//                                      splitting vertices on chart seams
//
// Units: a chart's UVs are in the mesh's object-space length units, scaled so
// that the chart's total UV area equals its total 3D area (an area-preserving
// scale; the shape comes from the parametrization). The packer works in texel
// units: the caller multiplies chart UVs by texels-per-unit (density times the
// instance's world scale) before packing.
#pragma once

#include <cstdint>
#include <vector>

#include "common/math.h"

namespace luxel::uv {

// One chart: a connected set of a mesh's triangles flattened to the plane
// without folds (every UV triangle has the orientation of the others and
// non-zero area, unless its 3D triangle has none).
struct Chart {
  std::vector<uint32_t> triangles;  // indices into the mesh's triangles (Mesh::indices / 3)
  std::vector<uint32_t> vertices;   // mesh vertex of each chart vertex (a mesh vertex on a
                                    // seam appears in several charts)
  std::vector<Vec2> uv;             // per chart vertex, object-space units (see above)
  std::vector<uint32_t> indices;    // 3 per chart triangle, into `vertices` / `uv`,
                                    // in the order of `triangles`
  double area_3d = 0;               // sum of the 3D triangle areas (object space)
};

}  // namespace luxel::uv
