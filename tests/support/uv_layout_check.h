// An independent check of a laid-out lightmap (tests and benches of uv/): a
// rasteriser at texel centres that counts the centres covered by two or more
// triangles over every placed instance, and the stretch (Sander et al. 2001,
// §3) of the final atlas UVs against world-space positions. It shares no code
// with uv/ or atlas/texel_raster so that a bug there cannot hide itself.
#pragma once

#include <cstdint>

#include "atlas/atlas.h"
#include "scene/scene.h"

namespace luxel::testing {

struct LayoutCheck {
  long long covered_texels = 0;      // texel centres inside at least one triangle
  long long overlapping_texels = 0;  // texel centres inside two or more triangles
  long long triangles = 0;           // triangles rasterised (all instances)
  long long zero_uv_triangles = 0;   // zero UV area: cover no centre
  // Of those, the ones with 3D area (the surface gets no texel), and their
  // world-space area.
  long long collapsed_triangles = 0;
  double collapsed_area = 0;
  long long outside_triangles = 0;  // with UV area: a corner outside [0,1]^2 or not finite
  long long outside_points = 0;     // zero UV area (covering nothing), outside [0,1]^2
  // Stretch of atlas UV against world positions over every triangle with 3D
  // area, normalised once for the whole atlas (one density): L2 is the
  // area-weighted RMS, Linf the largest; 1 is an isometry up to that scale.
  // Collapsed triangles are left out (they are counted above).
  double stretch_l2 = 1, stretch_linf = 1;
  // Texels per world unit, sqrt(texel area / world area), of the instance
  // with the lowest and the highest density (instances with area).
  double density_min = 0, density_max = 0;
  long long atlas_texels = 0;  // width * height
};

// Rasterises every triangle of every instance at the atlas's texel centres
// (i + 0.5, j + 0.5) in texel units, atlas_uv = uv1 * scale + offset evaluated
// in double. A centre on an edge shared by two triangles counts once (a
// top-left rule with each edge evaluated in one canonical direction), so a
// chart's own triangles never overlap each other.
LayoutCheck check_layout(const scene::Scene& scene, const atlas::Atlas& atlas);

}  // namespace luxel::testing
