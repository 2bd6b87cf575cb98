#include "atlas/seams.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <tuple>

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

// A seam of one mesh in uv1 space (before the instance's placement).
struct MeshSeam {
  Vec2 a0, a1, b0, b1;
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
  for (size_t i = 0; i < edges.size();) {
    size_t j = i + 1;
    while (j < edges.size() && same_edge(edges[i], edges[j])) ++j;
    if (j - i == 2 && smooth(edges[i], edges[i + 1]))
      out.seams.push_back({edges[i].uv_lo, edges[i].uv_hi, edges[i + 1].uv_lo, edges[i + 1].uv_hi});
    else if (j - i == 2)
      ++out.hard;
    else if (j - i > 2)
      ++out.non_manifold;
    i = j;
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
