#include "uv/charts.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "uv/chart_layout.h"
#include "uv/lscm.h"
#include "uv/parametrize.h"
#include "uv/segment.h"
#include "uv/stretch.h"
#include "uv/topology.h"
#include "uv/validate.h"

namespace luxel::uv {
namespace {

Status check_options(const ChartOptions& o) {
  auto in = [](double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; };
  if (!in(o.max_cone_half_angle_deg, 0, 89))
    return invalid_argument("chart options: max_cone_half_angle_deg must be in [0, 89]");
  if (!in(o.max_dihedral_deg, 0, 180))
    return invalid_argument("chart options: max_dihedral_deg must be in [0, 180]");
  if (!in(o.planar_cone_half_angle_deg, 0, 89))
    return invalid_argument("chart options: planar_cone_half_angle_deg must be in [0, 89]");
  if (!in(o.hard_edge_normal_deg, 0, 180))
    return invalid_argument("chart options: hard_edge_normal_deg must be in [0, 180]");
  if (!in(o.weld_relative_epsilon, 0, 1e-2))
    return invalid_argument("chart options: weld_relative_epsilon must be in [0, 0.01]");
  if (!in(o.compactness_weight, 0, 1e6))
    return invalid_argument("chart options: compactness_weight must be in [0, 1e6]");
  if (o.max_chart_triangles < 1)
    return invalid_argument("chart options: max_chart_triangles must be at least 1");
  if (!(o.max_aspect >= 1)) return invalid_argument("chart options: max_aspect must be at least 1");
  if (!(o.max_stretch_l2 == 0 || (std::isfinite(o.max_stretch_l2) && o.max_stretch_l2 >= 1)))
    return invalid_argument("chart options: max_stretch_l2 must be 0 (no limit) or at least 1");
  return Status::ok();
}

Status check_mesh(const scene::Mesh& mesh) {
  if (mesh.indices.size() % 3 != 0)
    return invalid_argument(strprintf("mesh '%s': %zu indices is not a multiple of 3",
                                      mesh.name.c_str(), mesh.indices.size()));
  if (!mesh.triangle_material.empty() && mesh.triangle_material.size() != mesh.triangle_count())
    return invalid_argument(strprintf("mesh '%s': %zu triangle materials for %zu triangles",
                                      mesh.name.c_str(), mesh.triangle_material.size(),
                                      mesh.triangle_count()));
  return Status::ok();
}

Chart to_chart(const scene::Mesh& mesh, const LocalChart& local, const std::vector<Vec2>& uv) {
  // Chart vertices are mesh vertices (in order of first use); each takes the
  // UV of its topological vertex.
  Chart c;
  c.triangles = local.triangles;
  c.area_3d = local.area_3d;
  std::vector<uint32_t> corners;
  corners.reserve(3 * local.triangles.size());
  for (uint32_t t : local.triangles)
    for (int k = 0; k < 3; ++k) corners.push_back(mesh.indices[3 * t + k]);
  std::vector<uint32_t> sorted = corners;
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  std::vector<int32_t> slot(sorted.size(), -1);
  c.indices.resize(corners.size());
  for (size_t i = 0; i < corners.size(); ++i) {
    const size_t s = std::lower_bound(sorted.begin(), sorted.end(), corners[i]) - sorted.begin();
    if (slot[s] < 0) {
      slot[s] = static_cast<int32_t>(c.vertices.size());
      c.vertices.push_back(corners[i]);
      c.uv.push_back(uv[local.indices[i]]);
    }
    c.indices[i] = static_cast<uint32_t>(slot[s]);
  }
  return c;
}

}  // namespace

Result<std::vector<Chart>> build_charts(const scene::Mesh& mesh, const ChartOptions& options,
                                        ChartStats* stats) {
  LUXEL_RETURN_IF_ERROR(check_options(options));
  LUXEL_RETURN_IF_ERROR(check_mesh(mesh));
  Result<Topology> topo_or = build_topology(mesh, options);
  if (!topo_or) return topo_or.status();
  const Topology& topo = topo_or.value();

  ChartStats st;
  st.triangles = mesh.triangle_count();
  st.degenerate_triangles = topo.degenerate_count;
  st.welded_vertices = topo.welded_count;
  const double planar_limit = options.planar_cone_half_angle_deg * std::numbers::pi / 180.0;

  std::vector<std::vector<uint32_t>> grown = grow_charts(topo, options);
  // Depth-first work list (last in, first out; parts pushed in reverse) so
  // that the output order follows the growth order and the split order.
  std::vector<std::vector<uint32_t>> work(grown.rbegin(), grown.rend());
  std::vector<Chart> charts;
  auto push_split = [&](const std::vector<uint32_t>& tris) {
    auto parts = split_chart(topo, tris);
    for (auto it = parts.rbegin(); it != parts.rend(); ++it) work.push_back(std::move(*it));
  };
  while (!work.empty()) {
    std::vector<uint32_t> tris = std::move(work.back());
    work.pop_back();
    const size_t n = tris.size();
    LocalChart local = make_local_chart(mesh, topo, std::move(tris));
    const bool planar = n == 1 || local.cone_half_angle <= planar_limit;
    if (planar) {
      project_planar(local);
    } else if (!solve_lscm(local)) {
      ++st.rejected_splits;
      push_split(local.triangles);
      continue;
    }
    LaidOutChart laid = lay_out_chart(local, options.rotate_to_min_rect);
    // A single triangle is valid by construction (its projection is exact);
    // larger charts are checked in the float UVs they are delivered in.
    if (n > 1 && find_chart_defect(laid.uv, local.indices) != ChartDefect::kNone) {
      ++st.rejected_splits;
      push_split(local.triangles);
      continue;
    }
    const double lo = std::min(laid.width, laid.height), hi = std::max(laid.width, laid.height);
    if (n > 2 && hi > options.max_aspect * lo) {
      ++st.aspect_splits;
      push_split(local.triangles);
      continue;
    }
    if (n > 1 && options.max_stretch_l2 > 0 &&
        indexed_stretch(local.position, laid.uv, local.indices).l2 > options.max_stretch_l2) {
      ++st.stretch_splits;
      push_split(local.triangles);
      continue;
    }
    ++(planar ? st.planar_charts : st.lscm_charts);
    charts.push_back(to_chart(mesh, local, laid.uv));
  }
  st.charts = charts.size();
  if (stats) *stats = st;
  return charts;
}

}  // namespace luxel::uv
