// Texture stretch of a parametrization (Sander, Snyder, Gortler, Hoppe 2001,
// "Texture mapping progressive meshes", §3).
//
// For the affine map S from a UV triangle to its 3D triangle, with Jacobian
// columns S_s, S_t (eq. 2) and singular values Gamma >= gamma:
//   L2(T)   = sqrt((Gamma^2 + gamma^2) / 2) = sqrt((a + c) / 2)
//   Linf(T) = Gamma
// where a = S_s.S_s, c = S_t.S_t. Over a set of triangles, L2 is the
// 3D-area-weighted root mean square and Linf the maximum. Both are multiplied
// by sqrt(sum A_uv / sum A_3d) (the normalisation of §3, so that a uniform UV
// scale changes nothing); with that, L2 >= 1 and L2 == 1 exactly when the map
// is an isometry up to that scale. A zero-area UV triangle whose 3D triangle
// has area gives infinite stretch.
#pragma once

#include <cstdint>
#include <vector>

#include "common/dvec3.h"
#include "common/math.h"
#include "scene/scene.h"
#include "uv/chart.h"

namespace luxel::uv {

struct Stretch {
  double l2 = 1.0;
  double linf = 1.0;
  double area_3d = 0;  // weight of this measurement (object space)
  double area_uv = 0;
};

// Unnormalised stretch of one triangle (area_3d and area_uv set; area_uv is
// the absolute UV area).
Stretch triangle_stretch(const DVec3 q[3], const Vec2 p[3]);

// Normalised stretch of indexed triangles (3 indices per triangle into both
// position and uv).
Stretch indexed_stretch(const std::vector<DVec3>& position, const std::vector<Vec2>& uv,
                        const std::vector<uint32_t>& indices);

// Normalised stretch of a chart's UVs against the mesh's triangles.
Stretch chart_stretch(const scene::Mesh& mesh, const Chart& chart);

// Over all charts of a mesh: L2 combines the charts' normalised L2 weighted by
// their 3D area, Linf is the largest chart Linf (each chart is normalised on
// its own, as each is scaled on its own before packing).
Stretch mesh_stretch(const scene::Mesh& mesh, const std::vector<Chart>& charts);

}  // namespace luxel::uv
