#include "support/uv_layout_check.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace luxel::testing {
namespace {

struct P2 {
  double x = 0, y = 0;
};

bool less(P2 a, P2 b) {
  return a.x < b.x || (a.x == b.x && a.y < b.y);
}

// Edge function of the directed edge a -> b at q (> 0: q left of the edge),
// always evaluated from the lexicographically smaller endpoint so that the
// two triangles sharing an edge get exactly opposite values.
double edge(P2 a, P2 b, P2 q) {
  if (less(b, a)) return -edge(b, a, q);
  return (b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x);
}

// Top-left rule for a counter-clockwise triangle with y up: a centre on a
// left edge (going down) or a top edge (horizontal, going left) is inside.
bool top_left(P2 a, P2 b) {
  return b.y < a.y || (b.y == a.y && b.x < a.x);
}

bool inside(double w, P2 a, P2 b) {
  return w > 0 || (w == 0 && top_left(a, b));
}

}  // namespace

LayoutCheck check_layout(const scene::Scene& scene, const atlas::Atlas& atlas) {
  LayoutCheck r;
  const int w = atlas.width, h = atlas.height;
  if (w <= 0 || h <= 0) return r;
  r.atlas_texels = static_cast<long long>(w) * h;
  std::vector<uint8_t> count(static_cast<size_t>(w) * static_cast<size_t>(h), 0);
  double sum_l2 = 0, max_linf = 0, area_3d = 0, area_uv = 0;
  for (uint32_t i = 0; i < scene.instances.size(); ++i) {
    const scene::Instance& inst = scene.instances[i];
    if (inst.mesh < 0 || static_cast<size_t>(inst.mesh) >= scene.meshes.size()) continue;
    const scene::Mesh& mesh = scene.meshes[static_cast<size_t>(inst.mesh)];
    const atlas::InstancePlacement& pl = atlas.placements[i];
    const Mat4& m = inst.object_to_world;
    double inst_world = 0, inst_texels = 0;
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
      ++r.triangles;
      P2 p[3];
      double q[3][3];
      bool outside = false;
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = mesh.indices[t + static_cast<size_t>(k)];
        const Vec2 uv = mesh.uv1[v];
        const double u = static_cast<double>(uv.x) * pl.scale[0] + pl.offset[0];
        const double s = static_cast<double>(uv.y) * pl.scale[1] + pl.offset[1];
        if (!(u >= 0 && u <= 1 && s >= 0 && s <= 1)) outside = true;
        p[k] = {u * w, s * h};
        const Vec3 x = mesh.positions[v];
        for (int c = 0; c < 3; ++c)
          q[k][c] = m.at(c, 0) * x.x + m.at(c, 1) * x.y + m.at(c, 2) * x.z + m.at(c, 3);
      }
      // Stretch of the map from atlas texels to world space (Sander et al.
      // 2001, eq. 2), accumulated unnormalised.
      const double twice_uv =
          (p[1].x - p[0].x) * (p[2].y - p[0].y) - (p[2].x - p[0].x) * (p[1].y - p[0].y);
      if (outside) {
        ++(twice_uv == 0 ? r.outside_points : r.outside_triangles);
        continue;
      }
      double e1[3], e2[3], n[3];
      for (int c = 0; c < 3; ++c) e1[c] = q[1][c] - q[0][c], e2[c] = q[2][c] - q[0][c];
      n[0] = e1[1] * e2[2] - e1[2] * e2[1];
      n[1] = e1[2] * e2[0] - e1[0] * e2[2];
      n[2] = e1[0] * e2[1] - e1[1] * e2[0];
      const double a3 = 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      if (a3 > 0 && twice_uv != 0) {
        double ss[3], st[3];
        for (int c = 0; c < 3; ++c) {
          ss[c] = (q[0][c] * (p[1].y - p[2].y) + q[1][c] * (p[2].y - p[0].y) +
                   q[2][c] * (p[0].y - p[1].y)) /
                  twice_uv;
          st[c] = (q[0][c] * (p[2].x - p[1].x) + q[1][c] * (p[0].x - p[2].x) +
                   q[2][c] * (p[1].x - p[0].x)) /
                  twice_uv;
        }
        const double a = ss[0] * ss[0] + ss[1] * ss[1] + ss[2] * ss[2];
        const double b = ss[0] * st[0] + ss[1] * st[1] + ss[2] * st[2];
        const double c = st[0] * st[0] + st[1] * st[1] + st[2] * st[2];
        sum_l2 += 0.5 * (a + c) * a3;
        max_linf = std::max(max_linf, 0.5 * ((a + c) + std::sqrt((a - c) * (a - c) + 4 * b * b)));
        area_3d += a3;
        area_uv += 0.5 * std::fabs(twice_uv);
      } else if (a3 > 0) {
        ++r.collapsed_triangles;
        r.collapsed_area += a3;
      }
      if (a3 > 0 && twice_uv != 0) inst_world += a3, inst_texels += 0.5 * std::fabs(twice_uv);
      if (twice_uv == 0) {
        ++r.zero_uv_triangles;
        continue;
      }
      if (twice_uv < 0) std::swap(p[1], p[2]);
      const double x0 = std::min({p[0].x, p[1].x, p[2].x});
      const double x1 = std::max({p[0].x, p[1].x, p[2].x});
      const double y0 = std::min({p[0].y, p[1].y, p[2].y});
      const double y1 = std::max({p[0].y, p[1].y, p[2].y});
      const int i0 = std::max(0, static_cast<int>(std::ceil(x0 - 0.5)));
      const int i1 = std::min(w - 1, static_cast<int>(std::floor(x1 - 0.5)));
      const int j0 = std::max(0, static_cast<int>(std::ceil(y0 - 0.5)));
      const int j1 = std::min(h - 1, static_cast<int>(std::floor(y1 - 0.5)));
      for (int j = j0; j <= j1; ++j)
        for (int ii = i0; ii <= i1; ++ii) {
          const P2 c{ii + 0.5, j + 0.5};
          if (!inside(edge(p[0], p[1], c), p[0], p[1]) ||
              !inside(edge(p[1], p[2], c), p[1], p[2]) || !inside(edge(p[2], p[0], c), p[2], p[0]))
            continue;
          uint8_t& n_cover =
              count[static_cast<size_t>(j) * static_cast<size_t>(w) + static_cast<size_t>(ii)];
          if (n_cover < 255) ++n_cover;
        }
    }
    if (inst_world > 0) {
      const double d = std::sqrt(inst_texels / inst_world);
      r.density_min = r.density_min > 0 ? std::min(r.density_min, d) : d;
      r.density_max = std::max(r.density_max, d);
    }
  }
  for (uint8_t c : count) {
    r.covered_texels += c >= 1;
    r.overlapping_texels += c >= 2;
  }
  if (area_3d > 0 && area_uv > 0) {
    // Normalise so that a uniform scale of the atlas changes nothing (§3).
    const double norm = std::sqrt(area_uv / area_3d);
    r.stretch_l2 = std::sqrt(sum_l2 / area_3d) * norm;
    r.stretch_linf = std::sqrt(max_linf) * norm;
  }
  return r;
}

}  // namespace luxel::testing
