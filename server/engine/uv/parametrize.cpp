#include "uv/parametrize.h"

#include <algorithm>
#include <cmath>

namespace luxel::uv {

LocalChart make_local_chart(const scene::Mesh& mesh, const Topology& topo,
                            std::vector<uint32_t> triangles) {
  LocalChart c;
  c.triangles = std::move(triangles);
  // Local vertices in order of first use, found through a sorted copy of the
  // welded ids (no hash map, so the numbering is reproducible).
  std::vector<uint32_t> ids;
  ids.reserve(3 * c.triangles.size());
  for (uint32_t t : c.triangles)
    for (int k = 0; k < 3; ++k) ids.push_back(topo.weld[mesh.indices[3 * t + k]]);
  std::vector<uint32_t> sorted = ids;
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  std::vector<int32_t> local(sorted.size(), -1);
  c.indices.resize(ids.size());
  DVec3 normal_sum{};
  for (size_t i = 0; i < ids.size(); ++i) {
    const size_t s = std::lower_bound(sorted.begin(), sorted.end(), ids[i]) - sorted.begin();
    if (local[s] < 0) {
      local[s] = static_cast<int32_t>(c.welded.size());
      c.welded.push_back(ids[i]);
      const Vec3 p = mesh.positions[mesh.indices[3 * c.triangles[i / 3] + i % 3]];
      c.position.push_back({p.x, p.y, p.z});
    }
    c.indices[i] = static_cast<uint32_t>(local[s]);
  }
  for (uint32_t t : c.triangles) {
    normal_sum = normal_sum + topo.normal[t] * topo.area[t];
    c.area_3d += topo.area[t];
  }
  const double len = std::sqrt(dot(normal_sum, normal_sum));
  c.mean_normal = len > 0 ? normal_sum * (1.0 / len) : topo.normal[c.triangles[0]];
  double min_cos = 1.0;
  for (uint32_t t : c.triangles) min_cos = std::min(min_cos, dot(c.mean_normal, topo.normal[t]));
  c.cone_half_angle = std::acos(std::clamp(min_cos, -1.0, 1.0));
  return c;
}

void project_planar(LocalChart& chart) {
  const DVec3 n = chart.mean_normal;
  // t: the world axis least aligned with n, made perpendicular to it.
  const double ax = std::fabs(n.x), ay = std::fabs(n.y), az = std::fabs(n.z);
  const DVec3 e =
      (ax <= ay && ax <= az) ? DVec3{1, 0, 0} : (ay <= az ? DVec3{0, 1, 0} : DVec3{0, 0, 1});
  const DVec3 t = normalize(e - n * dot(n, e));
  const DVec3 b = cross(n, t);
  // Relative to the first vertex, so that far-from-origin charts keep their
  // precision in the projection.
  const DVec3 o = chart.position[0];
  chart.uv.resize(chart.position.size());
  for (size_t i = 0; i < chart.position.size(); ++i) {
    const DVec3 d = chart.position[i] - o;
    chart.uv[i] = {dot(d, t), dot(d, b)};
  }
}

}  // namespace luxel::uv
