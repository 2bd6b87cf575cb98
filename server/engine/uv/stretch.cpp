#include "uv/stretch.h"

#include <algorithm>
#include <cmath>

namespace luxel::uv {

Stretch triangle_stretch(const DVec3 q[3], const Vec2 p[3]) {
  const double s1 = p[0].x, t1 = p[0].y, s2 = p[1].x, t2 = p[1].y, s3 = p[2].x, t3 = p[2].y;
  const double twice_uv = (s2 - s1) * (t3 - t1) - (s3 - s1) * (t2 - t1);
  const DVec3 n = cross(q[1] - q[0], q[2] - q[0]);
  Stretch r;
  r.area_3d = 0.5 * std::sqrt(dot(n, n));
  r.area_uv = 0.5 * std::fabs(twice_uv);
  if (twice_uv == 0) {
    r.l2 = r.linf = r.area_3d > 0 ? INFINITY : 1.0;
    return r;
  }
  // Eq. 2 (A = twice_uv / 2; the 1/(2A) factor).
  const DVec3 ss = (q[0] * (t2 - t3) + q[1] * (t3 - t1) + q[2] * (t1 - t2)) * (1.0 / twice_uv);
  const DVec3 st = (q[0] * (s3 - s2) + q[1] * (s1 - s3) + q[2] * (s2 - s1)) * (1.0 / twice_uv);
  const double a = dot(ss, ss), b = dot(ss, st), c = dot(st, st);
  r.l2 = std::sqrt(0.5 * (a + c));
  r.linf = std::sqrt(0.5 * ((a + c) + std::sqrt((a - c) * (a - c) + 4 * b * b)));
  return r;
}

namespace {

// Accumulates triangles; corner(k, q, p) fills triangle k's corners.
template <typename Corners>
Stretch accumulate(size_t count, Corners corner) {
  double sum_l2 = 0, linf = 0, a3 = 0, auv = 0;
  for (size_t k = 0; k < count; ++k) {
    DVec3 q[3];
    Vec2 p[3];
    corner(k, q, p);
    const Stretch t = triangle_stretch(q, p);
    sum_l2 += t.l2 * t.l2 * t.area_3d;
    linf = std::max(linf, t.linf);
    a3 += t.area_3d;
    auv += t.area_uv;
  }
  Stretch r;
  r.area_3d = a3;
  r.area_uv = auv;
  if (a3 > 0) {
    const double norm = std::sqrt(auv / a3);
    r.l2 = std::sqrt(sum_l2 / a3) * norm;
    r.linf = linf * norm;
  }
  return r;
}

}  // namespace

Stretch indexed_stretch(const std::vector<DVec3>& position, const std::vector<Vec2>& uv,
                        const std::vector<uint32_t>& indices) {
  return accumulate(indices.size() / 3, [&](size_t k, DVec3* q, Vec2* p) {
    for (int j = 0; j < 3; ++j) {
      q[j] = position[indices[3 * k + j]];
      p[j] = uv[indices[3 * k + j]];
    }
  });
}

Stretch chart_stretch(const scene::Mesh& mesh, const Chart& chart) {
  return accumulate(chart.triangles.size(), [&](size_t k, DVec3* q, Vec2* p) {
    for (int j = 0; j < 3; ++j) {
      const Vec3 v = mesh.positions[mesh.indices[3 * chart.triangles[k] + j]];
      q[j] = {v.x, v.y, v.z};
      p[j] = chart.uv[chart.indices[3 * k + j]];
    }
  });
}

Stretch mesh_stretch(const scene::Mesh& mesh, const std::vector<Chart>& charts) {
  double sum_l2 = 0, linf = 0, a3 = 0, auv = 0;
  for (const Chart& c : charts) {
    const Stretch s = chart_stretch(mesh, c);
    sum_l2 += s.l2 * s.l2 * s.area_3d;
    linf = std::max(linf, s.linf);
    a3 += s.area_3d;
    auv += s.area_uv;
  }
  Stretch r;
  r.area_3d = a3;
  r.area_uv = auv;
  if (a3 > 0) {
    r.l2 = std::sqrt(sum_l2 / a3);
    r.linf = linf;
  }
  return r;
}

}  // namespace luxel::uv
