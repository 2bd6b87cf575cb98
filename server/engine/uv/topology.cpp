#include "uv/topology.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <numbers>
#include <unordered_map>

#include "common/hash.h"

namespace luxel::uv {
namespace {

DVec3 to_d(Vec3 v) {
  return {v.x, v.y, v.z};
}

double deg_to_rad(double d) {
  return d * std::numbers::pi / 180.0;
}

// FNV-1a a word at a time. The hash only places cells in buckets (the grid is
// never iterated), so the welds do not depend on its values.
struct CellHash {
  size_t operator()(const std::array<int64_t, 3>& c) const {
    uint64_t h = kFnv1aBasis;
    for (int64_t v : c) h = fnv1a_step(h, static_cast<uint64_t>(v));
    return static_cast<size_t>(h);
  }
};

// Welds vertices within eps (Chebyshev distance, so a grid of eps cells and
// its 27-cell neighbourhood finds every candidate). Each vertex joins the
// first earlier representative in range, so the result depends only on the
// vertex order. eps == 0 welds bit-identical positions only.
std::vector<uint32_t> weld_positions(const std::vector<Vec3>& p, const std::vector<uint8_t>& used,
                                     double eps, size_t* count) {
  std::vector<uint32_t> weld(p.size());
  std::vector<uint32_t> rep_of_id;  // welded id -> representative vertex
  std::unordered_map<std::array<int64_t, 3>, std::vector<uint32_t>, CellHash> grid;
  const double inv = eps > 0 ? 1.0 / eps : 0.0;
  auto cell_of = [&](Vec3 v) {
    std::array<int64_t, 3> c{};
    for (int a = 0; a < 3; ++a) {
      if (eps > 0) {
        c[a] = static_cast<int64_t>(std::floor(std::clamp(double(v[a]) * inv, -4e18, 4e18)));
      } else {
        uint32_t bits;
        const float f = v[a] == 0.0f ? 0.0f : v[a];  // -0 and +0 weld
        std::memcpy(&bits, &f, 4);
        c[a] = bits;
      }
    }
    return c;
  };
  for (uint32_t i = 0; i < p.size(); ++i) {
    if (!used[i]) {  // unreferenced (possibly non-finite): its own vertex
      weld[i] = static_cast<uint32_t>(rep_of_id.size());
      rep_of_id.push_back(i);
      continue;
    }
    const auto c = cell_of(p[i]);
    int64_t found = -1;
    const int r = eps > 0 ? 1 : 0;
    for (int dx = -r; dx <= r && found < 0; ++dx)
      for (int dy = -r; dy <= r && found < 0; ++dy)
        for (int dz = -r; dz <= r && found < 0; ++dz) {
          auto it = grid.find({c[0] + dx, c[1] + dy, c[2] + dz});
          if (it == grid.end()) continue;
          for (uint32_t q : it->second) {
            const Vec3 d = p[q] - p[i];
            if (std::max({std::fabs(double(d.x)), std::fabs(double(d.y)),
                          std::fabs(double(d.z))}) <= eps) {
              found = weld[q];
              break;
            }
          }
        }
    if (found >= 0) {
      weld[i] = static_cast<uint32_t>(found);
    } else {
      weld[i] = static_cast<uint32_t>(rep_of_id.size());
      rep_of_id.push_back(i);
      grid[c].push_back(i);
    }
  }
  *count = rep_of_id.size();
  return weld;
}

struct EdgeRef {
  uint32_t lo, hi;  // welded endpoints, lo < hi
  uint32_t tri;
  uint8_t edge;
  bool operator<(const EdgeRef& o) const {
    if (lo != o.lo) return lo < o.lo;
    if (hi != o.hi) return hi < o.hi;
    if (tri != o.tri) return tri < o.tri;
    return edge < o.edge;
  }
};

}  // namespace

Result<Topology> build_topology(const scene::Mesh& mesh, const ChartOptions& options) {
  const size_t n_tri = mesh.triangle_count();
  const auto& idx = mesh.indices;
  const auto& pos = mesh.positions;
  Topology topo;
  std::vector<uint8_t> used(pos.size(), 0);
  Bounds3 bounds;
  for (size_t t = 0; t < n_tri; ++t) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = idx[3 * t + k];
      if (v >= pos.size())
        return invalid_argument(
            strprintf("mesh '%s' triangle %zu: vertex index %u out of range (%zu vertices)",
                      mesh.name.c_str(), t, v, pos.size()));
      if (!is_finite(pos[v]))
        return invalid_argument(
            strprintf("mesh '%s' triangle %zu: vertex %u has a non-finite position",
                      mesh.name.c_str(), t, v));
      used[v] = 1;
      bounds.extend(pos[v]);
    }
  }
  const double diag = bounds.empty() ? 0.0 : length(bounds.extent());
  topo.weld = weld_positions(pos, used, options.weld_relative_epsilon * diag, &topo.welded_count);

  topo.valid.assign(n_tri, 0);
  topo.normal.assign(n_tri, DVec3{});
  topo.centroid.assign(n_tri, DVec3{});
  topo.area.assign(n_tri, 0.0);
  topo.edge_length.assign(3 * n_tri, 0.0);
  topo.neighbour.assign(3 * n_tri, -1);
  std::vector<EdgeRef> edges;
  edges.reserve(3 * n_tri);
  for (size_t t = 0; t < n_tri; ++t) {
    const DVec3 a = to_d(pos[idx[3 * t]]), b = to_d(pos[idx[3 * t + 1]]),
                c = to_d(pos[idx[3 * t + 2]]);
    topo.centroid[t] = (a + b + c) * (1.0 / 3.0);
    const DVec3 n = cross(b - a, c - a);
    const double twice_area = std::sqrt(dot(n, n));
    const double longest = std::max({dot(b - a, b - a), dot(c - b, c - b), dot(a - c, a - c)});
    const uint32_t w0 = topo.weld[idx[3 * t]], w1 = topo.weld[idx[3 * t + 1]],
                   w2 = topo.weld[idx[3 * t + 2]];
    // Welding can collapse a tiny triangle; it is then as degenerate as a
    // zero-area one (two of its corners are the same topological vertex).
    if (!(twice_area > kDegenerateSine * longest) || w0 == w1 || w1 == w2 || w2 == w0) {
      ++topo.degenerate_count;
      continue;
    }
    topo.valid[t] = 1;
    topo.normal[t] = n * (1.0 / twice_area);
    topo.area[t] = 0.5 * twice_area;
    topo.edge_length[3 * t] = std::sqrt(dot(b - a, b - a));
    topo.edge_length[3 * t + 1] = std::sqrt(dot(c - b, c - b));
    topo.edge_length[3 * t + 2] = std::sqrt(dot(a - c, a - c));
    const uint32_t w[3] = {w0, w1, w2};
    for (uint8_t e = 0; e < 3; ++e) {
      const uint32_t p = w[e], q = w[(e + 1) % 3];
      edges.push_back({std::min(p, q), std::max(p, q), static_cast<uint32_t>(t), e});
    }
  }
  std::sort(edges.begin(), edges.end());

  const double cos_dihedral = std::cos(deg_to_rad(options.max_dihedral_deg));
  const double cos_hard = std::cos(deg_to_rad(options.hard_edge_normal_deg));
  const bool has_normals = mesh.normals.size() == pos.size();
  const bool has_materials = mesh.triangle_material.size() == n_tri;
  auto normals_agree = [&](uint32_t v1, uint32_t v2) {
    if (v1 == v2 || !has_normals) return true;
    const DVec3 n1 = to_d(mesh.normals[v1]), n2 = to_d(mesh.normals[v2]);
    const double l = std::sqrt(dot(n1, n1) * dot(n2, n2));
    return l > 0 && dot(n1, n2) >= cos_hard * l;
  };
  for (size_t i = 0; i < edges.size();) {
    size_t j = i + 1;
    while (j < edges.size() && edges[j].lo == edges[i].lo && edges[j].hi == edges[i].hi) ++j;
    if (j - i == 2) {  // manifold interior edge; more than two sides is a cut
      const EdgeRef& e1 = edges[i];
      const EdgeRef& e2 = edges[i + 1];
      const uint32_t t1 = e1.tri, t2 = e2.tri;
      // Mesh vertices at the edge's start and end in each triangle.
      const uint32_t a1 = idx[3 * t1 + e1.edge], b1 = idx[3 * t1 + (e1.edge + 1) % 3];
      const uint32_t a2 = idx[3 * t2 + e2.edge], b2 = idx[3 * t2 + (e2.edge + 1) % 3];
      // Consistent winding traverses a shared edge in opposite directions;
      // a chart across an inconsistently wound edge could not keep all its
      // UV triangles in one orientation.
      const bool opposite = topo.weld[a1] == topo.weld[b2] && topo.weld[b1] == topo.weld[a2];
      const bool same_material =
          !has_materials || mesh.triangle_material[t1] == mesh.triangle_material[t2];
      const bool smooth = dot(topo.normal[t1], topo.normal[t2]) >= cos_dihedral;
      if (opposite && same_material && smooth && normals_agree(a1, b2) && normals_agree(b1, a2)) {
        topo.neighbour[3 * t1 + e1.edge] = static_cast<int32_t>(t2);
        topo.neighbour[3 * t2 + e2.edge] = static_cast<int32_t>(t1);
      }
    }
    i = j;
  }
  return topo;
}

}  // namespace luxel::uv
