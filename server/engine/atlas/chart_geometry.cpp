#include "atlas/chart_geometry.h"

#include <algorithm>
#include <cstdint>

namespace luxel::atlas {

bool is_zero_area(double ax, double ay, double bx, double by, double cx, double cy) {
  const double e1x = bx - ax, e1y = by - ay, e2x = cx - ax, e2y = cy - ay;
  const double cross = e1x * e2y - e1y * e2x;
  const double lengths = std::sqrt((e1x * e1x + e1y * e1y) * (e2x * e2x + e2y * e2y));
  return !(std::fabs(cross) > 1e-10 * lengths);
}

Result<MeshUvLayout> measure_mesh_uvs(const scene::Mesh& mesh) {
  const char* name = mesh.name.c_str();
  if (mesh.uv1.empty() || !mesh.has_lightmap_uvs)
    return invalid_argument(strprintf(
        "mesh '%s' has no TEXCOORD_1 lightmap UVs (bake with --uv auto or generate to generate "
        "them)",
        name));
  if (mesh.uv1.size() != mesh.positions.size())
    return invalid_argument(strprintf("mesh '%s' has %zu TEXCOORD_1 values for %zu vertices", name,
                                      mesh.uv1.size(), mesh.positions.size()));
  if (mesh.triangle_count() == 0)
    return invalid_argument(
        strprintf("mesh '%s' has no triangles to lay out in the lightmap", name));
  MeshUvLayout layout;
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    double u[3], v[3];
    for (int k = 0; k < 3; ++k) {
      const uint32_t index = mesh.indices[t * 3 + static_cast<size_t>(k)];
      if (index >= mesh.uv1.size())
        return invalid_argument(
            strprintf("mesh '%s' triangle %zu: index %u is out of range", name, t, index));
      const Vec2 uv = mesh.uv1[index];
      if (!std::isfinite(uv.x) || !std::isfinite(uv.y))
        return invalid_argument(
            strprintf("mesh '%s' vertex %u: TEXCOORD_1 is not finite", name, index));
      u[k] = uv.x;
      v[k] = uv.y;
      layout.bounds.lo[0] = std::min(layout.bounds.lo[0], u[k]);
      layout.bounds.lo[1] = std::min(layout.bounds.lo[1], v[k]);
      layout.bounds.hi[0] = std::max(layout.bounds.hi[0], u[k]);
      layout.bounds.hi[1] = std::max(layout.bounds.hi[1], v[k]);
    }
    if (is_zero_area(u[0], v[0], u[1], v[1], u[2], v[2])) {
      ++layout.zero_area_triangles;
      continue;
    }
    layout.area += 0.5 * std::fabs((u[1] - u[0]) * (v[2] - v[0]) - (v[1] - v[0]) * (u[2] - u[0]));
  }
  if (layout.zero_area_triangles == mesh.triangle_count())
    return invalid_argument(strprintf(
        "mesh '%s' has no usable TEXCOORD_1 lightmap UVs: all %zu triangles have zero UV area",
        name, mesh.triangle_count()));
  return layout;
}

double instance_world_area(const scene::Mesh& mesh, const scene::Instance& instance) {
  double area = 0;
  for (size_t t = 0; t < mesh.triangle_count(); ++t)
    area += transformed_triangle_area(instance.object_to_world, mesh.positions[mesh.indices[t * 3]],
                                      mesh.positions[mesh.indices[t * 3 + 1]],
                                      mesh.positions[mesh.indices[t * 3 + 2]]);
  return area;
}

bool instances_share_uv_space(const scene::Scene& scene, int check_resolution) {
  const int res = check_resolution;
  const double r = res;
  std::vector<int32_t> owner(static_cast<size_t>(res) * static_cast<size_t>(res), -1);
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    const scene::Mesh& mesh = scene.meshes[static_cast<size_t>(scene.instances[i].mesh)];
    const int32_t id = static_cast<int32_t>(i);
    for (size_t t = 0; t < mesh.triangle_count(); ++t) {
      double x[3], y[3];
      for (int k = 0; k < 3; ++k) {
        const Vec2 uv = mesh.uv1[mesh.indices[t * 3 + static_cast<size_t>(k)]];
        x[k] = uv.x * r;
        y[k] = uv.y * r;
      }
      if (is_zero_area(x[0], y[0], x[1], y[1], x[2], y[2])) continue;
      const double orient =
          (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]) > 0 ? 1 : -1;
      // Texel centres (i + 0.5) inside the bounding box, clamped to the grid
      // in double first (UVs may be far outside [0,1]).
      auto first = [&](double lo) {
        return static_cast<int>(std::clamp(std::ceil(lo - 0.5), 0.0, r));
      };
      auto last = [&](double hi) {
        return static_cast<int>(std::clamp(std::floor(hi - 0.5), -1.0, r - 1));
      };
      const int x0 = first(std::min({x[0], x[1], x[2]})), x1 = last(std::max({x[0], x[1], x[2]}));
      const int y0 = first(std::min({y[0], y[1], y[2]})), y1 = last(std::max({y[0], y[1], y[2]}));
      for (int ty = y0; ty <= y1; ++ty)
        for (int tx = x0; tx <= x1; ++tx) {
          const double px = tx + 0.5, py = ty + 0.5;
          bool inside = true;
          for (int k = 0; k < 3 && inside; ++k) {
            const int n = (k + 1) % 3;
            inside = orient * ((x[n] - x[k]) * (py - y[k]) - (y[n] - y[k]) * (px - x[k])) >= 0;
          }
          if (!inside) continue;
          int32_t& cell =
              owner[static_cast<size_t>(ty) * static_cast<size_t>(res) + static_cast<size_t>(tx)];
          if (cell >= 0 && cell != id) return true;
          cell = id;
        }
    }
  }
  return false;
}

}  // namespace luxel::atlas
