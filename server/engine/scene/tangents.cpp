// See tangents.h.
#include "scene/tangents.h"

#include <array>
#include <cmath>

namespace luxel::scene {
namespace {

// Any unit vector orthogonal to n (Duff et al. 2017, as kernels' lux_onb).
Vec3 any_tangent(Vec3 n) {
  const float sign = std::copysign(1.0f, n.z);
  const float a = -1.0f / (sign + n.z);
  return {1.0f + sign * n.x * n.x * a, sign * n.x * n.y * a, -sign * n.x};
}

}  // namespace

std::vector<Vec4> generate_tangents(const std::vector<Vec3>& positions,
                                    const std::vector<Vec3>& normals, const std::vector<Vec2>& uvs,
                                    const std::vector<uint32_t>& indices) {
  const size_t n = positions.size();
  // Sums in double: long thin triangles give large, cancelling gradients.
  std::vector<std::array<double, 6>> sum(n, std::array<double, 6>{});
  for (size_t t = 0; t + 2 < indices.size(); t += 3) {
    const uint32_t i0 = indices[t], i1 = indices[t + 1], i2 = indices[t + 2];
    if (i0 >= n || i1 >= n || i2 >= n || i0 >= uvs.size() || i1 >= uvs.size() || i2 >= uvs.size())
      continue;
    double e1[3], e2[3];
    for (int k = 0; k < 3; ++k) {
      e1[k] = double(positions[i1][k]) - double(positions[i0][k]);
      e2[k] = double(positions[i2][k]) - double(positions[i0][k]);
    }
    const double du1 = double(uvs[i1].x) - uvs[i0].x, dv1 = double(uvs[i1].y) - uvs[i0].y;
    const double du2 = double(uvs[i2].x) - uvs[i0].x, dv2 = double(uvs[i2].y) - uvs[i0].y;
    const double det = du1 * dv2 - du2 * dv1;
    if (!(std::fabs(det) > 0.0) || !std::isfinite(det)) continue;
    // [dP/du dP/dv] = [e1 e2] [du1 du2; dv1 dv2]^-1, weighted by |det| (the
    // triangle's UV area) so that tiny triangles count little.
    const double w = std::fabs(det) / det;
    std::array<double, 6> g;
    for (int k = 0; k < 3; ++k) {
      g[static_cast<size_t>(k)] = (e1[k] * dv2 - e2[k] * dv1) * w;
      g[static_cast<size_t>(k) + 3] = (e2[k] * du1 - e1[k] * du2) * w;
    }
    bool finite = true;
    for (double x : g) finite = finite && std::isfinite(x);
    if (!finite) continue;
    for (uint32_t v : {i0, i1, i2})
      for (size_t k = 0; k < 6; ++k) sum[v][k] += g[k];
  }
  std::vector<Vec4> out(n);
  for (size_t v = 0; v < n; ++v) {
    const Vec3 nv = v < normals.size() ? normalize(normals[v]) : Vec3{0, 0, 1};
    const double nd[3] = {nv.x, nv.y, nv.z};
    const double* s = sum[v].data();
    const double dn = s[0] * nd[0] + s[1] * nd[1] + s[2] * nd[2];
    double t[3] = {s[0] - nd[0] * dn, s[1] - nd[1] * dn, s[2] - nd[2] * dn};
    const double len = std::sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    if (!(len > 0.0) || !std::isfinite(len) || !is_finite(nv)) {
      const Vec3 a = is_finite(nv) ? any_tangent(nv) : Vec3{1, 0, 0};
      out[v] = {a.x, a.y, a.z, 1.0f};
      continue;
    }
    for (double& c : t) c /= len;
    // cross(n, t) against dP/dv: along +v means a mirrored mapping (w = -1).
    const double b[3] = {nd[1] * t[2] - nd[2] * t[1], nd[2] * t[0] - nd[0] * t[2],
                         nd[0] * t[1] - nd[1] * t[0]};
    const double along_v = b[0] * s[3] + b[1] * s[4] + b[2] * s[5];
    out[v] = {static_cast<float>(t[0]), static_cast<float>(t[1]), static_cast<float>(t[2]),
              along_v > 0.0 ? -1.0f : 1.0f};
  }
  return out;
}

}  // namespace luxel::scene
