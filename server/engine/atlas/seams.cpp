#include "atlas/seams.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <tuple>
#include <utility>

namespace luxel::atlas {
namespace {

using Key = std::array<int64_t, 3>;

// One triangle edge, oriented so that `lo` is the smaller quantised endpoint:
// both triangles of a shared edge then list its vertices in the same order.
struct EdgeRecord {
  Key lo, hi;
  uint32_t triangle;
  Vec2 uv_lo, uv_hi;
  Vec3 n_lo, n_hi;
};

bool same_edge(const EdgeRecord& x, const EdgeRecord& y) {
  return x.lo == y.lo && x.hi == y.hi;
}

// A seam of one mesh in uv1 space (before the instance's placement), with
// the uv1 bounds of the chart on each side.
struct MeshSeam {
  Vec2 a0, a1, b0, b1;
  Vec2 chart_a_lo, chart_a_hi, chart_b_lo, chart_b_hi;
};

struct MeshSeams {
  std::vector<MeshSeam> seams;
  size_t non_manifold = 0, hard = 0;
};

Vec3 unit_or_zero(Vec3 n) {
  const float len = std::sqrt(dot(n, n));
  return len > 0 && std::isfinite(len) ? n * (1.0f / len) : Vec3{};
}

// The shading normals of both triangles agree at both endpoints: the
// surface is smooth across the edge. At a hard edge (split normals) the
// lighting itself is discontinuous, and stitching would smear it.
bool smooth(const EdgeRecord& x, const EdgeRecord& y) {
  constexpr float kCosSmooth = 0.999f;  // about 2.6 degrees
  return dot(x.n_lo, y.n_lo) >= kCosSmooth && dot(x.n_hi, y.n_hi) >= kCosSmooth;
}

// Union-find over triangles: charts are triangles joined by edges whose two
// uv1 images coincide (the same rule the denoiser's chart labels follow).
struct Charts {
  std::vector<uint32_t> parent;
  explicit Charts(size_t n) : parent(n) {
    for (size_t i = 0; i < n; ++i) parent[i] = static_cast<uint32_t>(i);
  }
  uint32_t find(uint32_t t) {
    while (parent[t] != t) t = parent[t] = parent[parent[t]];
    return t;
  }
  void join(uint32_t a, uint32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

MeshSeams mesh_seams(const scene::Mesh& mesh) {
  MeshSeams out;
  if (mesh.positions.empty() || mesh.uv1.size() != mesh.positions.size()) return out;
  Vec3 lo = mesh.positions[0], hi = lo;
  for (const Vec3& p : mesh.positions)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], p[k]);
      hi[k] = std::max(hi[k], p[k]);
    }
  double extent = 0;
  for (int k = 0; k < 3; ++k) extent = std::max(extent, double(hi[k]) - double(lo[k]));
  if (!(extent > 0) || !std::isfinite(extent)) return out;
  const double quantum = extent * 0x1p-20;
  auto quantise = [&](const Vec3& p) {
    Key k;
    for (int i = 0; i < 3; ++i) k[i] = std::llround((double(p[i]) - double(lo[i])) / quantum);
    return k;
  };
  std::vector<EdgeRecord> edges;
  edges.reserve(mesh.indices.size());
  for (uint32_t t = 0; t < mesh.triangle_count(); ++t)
    for (int e = 0; e < 3; ++e) {
      const uint32_t i = mesh.indices[3 * t + e], j = mesh.indices[3 * t + (e + 1) % 3];
      const bool normals = mesh.normals.size() == mesh.positions.size();
      EdgeRecord r{quantise(mesh.positions[i]),
                   quantise(mesh.positions[j]),
                   t,
                   mesh.uv1[i],
                   mesh.uv1[j],
                   normals ? unit_or_zero(mesh.normals[i]) : Vec3{0, 0, 1},
                   normals ? unit_or_zero(mesh.normals[j]) : Vec3{0, 0, 1}};
      if (r.lo == r.hi) continue;  // collapsed edge: no surface to join
      if (r.hi < r.lo) {
        std::swap(r.lo, r.hi);
        std::swap(r.uv_lo, r.uv_hi);
        std::swap(r.n_lo, r.n_hi);
      }
      edges.push_back(r);
    }
  std::sort(edges.begin(), edges.end(), [](const EdgeRecord& x, const EdgeRecord& y) {
    return std::tie(x.lo, x.hi, x.triangle) < std::tie(y.lo, y.hi, y.triangle);
  });
  Charts charts(mesh.triangle_count());
  // Split vertices carry equal or nearly equal copies of one uv1.
  auto same_uv = [](Vec2 p, Vec2 q) {
    return std::abs(p.x - q.x) <= 1e-6f && std::abs(p.y - q.y) <= 1e-6f;
  };
  std::vector<std::pair<uint32_t, uint32_t>> seam_triangles;
  for (size_t i = 0; i < edges.size();) {
    size_t j = i + 1;
    while (j < edges.size() && same_edge(edges[i], edges[j])) ++j;
    const EdgeRecord &x = edges[i], &y = edges[std::min(i + 1, edges.size() - 1)];
    if (j - i == 2 && same_uv(x.uv_lo, y.uv_lo) && same_uv(x.uv_hi, y.uv_hi))
      charts.join(x.triangle, y.triangle);  // not a seam: one chart continues
    else if (j - i == 2 && smooth(x, y)) {
      out.seams.push_back({x.uv_lo, x.uv_hi, y.uv_lo, y.uv_hi, {}, {}, {}, {}});
      seam_triangles.emplace_back(x.triangle, y.triangle);
    } else if (j - i == 2)
      ++out.hard;
    else if (j - i > 2)
      ++out.non_manifold;
    i = j;
  }
  // uv1 bounds of every chart, for each seam's two sides.
  constexpr float kInf = std::numeric_limits<float>::infinity();
  std::vector<Vec2> lo_of(mesh.triangle_count(), Vec2{kInf, kInf}),
      hi_of(mesh.triangle_count(), Vec2{-kInf, -kInf});
  for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
    const uint32_t c = charts.find(t);
    for (int k = 0; k < 3; ++k) {
      const Vec2 uv = mesh.uv1[mesh.indices[3 * t + k]];
      lo_of[c] = {std::min(lo_of[c].x, uv.x), std::min(lo_of[c].y, uv.y)};
      hi_of[c] = {std::max(hi_of[c].x, uv.x), std::max(hi_of[c].y, uv.y)};
    }
  }
  for (size_t s = 0; s < out.seams.size(); ++s) {
    const uint32_t ca = charts.find(seam_triangles[s].first),
                   cb = charts.find(seam_triangles[s].second);
    out.seams[s].chart_a_lo = lo_of[ca];
    out.seams[s].chart_a_hi = hi_of[ca];
    out.seams[s].chart_b_lo = lo_of[cb];
    out.seams[s].chart_b_hi = hi_of[cb];
  }
  return out;
}

Vec2 to_texels(const Atlas& atlas, uint32_t instance, Vec2 uv1) {
  const Vec2 a = atlas.to_atlas(instance, uv1);
  return {a.x * float(atlas.width), a.y * float(atlas.height)};
}

float distance(Vec2 p, Vec2 q) {
  return std::hypot(p.x - q.x, p.y - q.y);
}

// The narrower side, in texels, of the atlas image of the uv1 box [lo, hi]
// (the placement may rotate a chart, so all four corners are mapped).
float box_width_texels(const Atlas& atlas, uint32_t instance, Vec2 lo, Vec2 hi) {
  Vec2 a_lo{std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity()};
  Vec2 a_hi{-a_lo.x, -a_lo.y};
  for (const Vec2 c : {lo, hi, Vec2{lo.x, hi.y}, Vec2{hi.x, lo.y}}) {
    const Vec2 t = to_texels(atlas, instance, c);
    a_lo = {std::min(a_lo.x, t.x), std::min(a_lo.y, t.y)};
    a_hi = {std::max(a_hi.x, t.x), std::max(a_hi.y, t.y)};
  }
  return std::min(a_hi.x - a_lo.x, a_hi.y - a_lo.y);
}

}  // namespace

SeamSet find_seams(const scene::Scene& scene, const Atlas& atlas) {
  SeamSet set;
  std::vector<MeshSeams> per_mesh(scene.meshes.size());
  std::vector<bool> done(scene.meshes.size(), false);
  const int page_h = std::max(1, atlas.page_height());
  auto page_of = [&](Vec2 p, Vec2 q) {
    const int page = static_cast<int>(std::floor(0.5f * (p.y + q.y) / float(page_h)));
    return std::clamp(page, 0, std::max(0, atlas.pages - 1));
  };
  constexpr float kSameImage = 1e-3f;  // texels
  for (uint32_t inst = 0; inst < scene.instances.size() && inst < atlas.placements.size(); ++inst) {
    const int m = scene.instances[inst].mesh;
    if (m < 0 || size_t(m) >= scene.meshes.size()) continue;
    if (!done[m]) {
      per_mesh[m] = mesh_seams(scene.meshes[m]);
      done[m] = true;
    }
    set.non_manifold += per_mesh[m].non_manifold;
    set.hard_edges += per_mesh[m].hard;
    for (const MeshSeam& s : per_mesh[m].seams) {
      SeamEdge e;
      e.instance = inst;
      e.a0 = to_texels(atlas, inst, s.a0);
      e.a1 = to_texels(atlas, inst, s.a1);
      e.b0 = to_texels(atlas, inst, s.b0);
      e.b1 = to_texels(atlas, inst, s.b1);
      e.chart_texels = std::min(box_width_texels(atlas, inst, s.chart_a_lo, s.chart_a_hi),
                                box_width_texels(atlas, inst, s.chart_b_lo, s.chart_b_hi));
      if (distance(e.a0, e.b0) <= kSameImage && distance(e.a1, e.b1) <= kSameImage) continue;
      if (distance(e.a0, e.a1) <= kSameImage || distance(e.b0, e.b1) <= kSameImage) {
        ++set.degenerate;
        continue;
      }
      const int pa = page_of(e.a0, e.a1), pb = page_of(e.b0, e.b1);
      if (pa != pb) {
        ++set.cross_page;
        continue;
      }
      e.page = pa;
      const float shift = float(pa) * float(page_h);
      for (Vec2* p : {&e.a0, &e.a1, &e.b0, &e.b1}) p->y -= shift;
      set.edges.push_back(e);
    }
  }
  return set;
}

}  // namespace luxel::atlas
