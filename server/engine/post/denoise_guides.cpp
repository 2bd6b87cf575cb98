#include "post/denoise_guides.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <numeric>
#include <unordered_map>

#include "atlas/texel_raster.h"
#include "kernels/shared/sample_info.h"

namespace luxel::pipeline {
namespace {

uint32_t find_root(std::vector<uint32_t>& parent, uint32_t i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

uint64_t uv_key(Vec2 uv) {
  // +0.0f and -0.0f are the same point.
  const float u = uv.x == 0.0f ? 0.0f : uv.x, v = uv.y == 0.0f ? 0.0f : uv.y;
  return (uint64_t{std::bit_cast<uint32_t>(u)} << 32) | std::bit_cast<uint32_t>(v);
}

}  // namespace

uint32_t label_uv_charts(const scene::Mesh& mesh, std::vector<uint32_t>& chart_of_triangle) {
  const size_t triangles = mesh.indices.size() / 3;
  std::vector<uint32_t> parent(triangles);
  std::iota(parent.begin(), parent.end(), 0u);
  // Split vertices (same UV, other normal) still join: the key is the UV value.
  std::unordered_map<uint64_t, uint32_t> first_at;
  first_at.reserve(mesh.indices.size());
  for (size_t t = 0; t < triangles; ++t)
    for (int k = 0; k < 3; ++k) {
      const uint64_t key = uv_key(mesh.uv1[mesh.indices[t * 3 + size_t(k)]]);
      auto [it, inserted] = first_at.try_emplace(key, static_cast<uint32_t>(t));
      if (!inserted) {
        const uint32_t a = find_root(parent, it->second), b = find_root(parent, uint32_t(t));
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
      }
    }
  chart_of_triangle.assign(triangles, 0);
  std::vector<uint32_t> label(triangles, UINT32_MAX);
  uint32_t count = 0;
  for (size_t t = 0; t < triangles; ++t) {
    const uint32_t r = find_root(parent, uint32_t(t));
    if (label[r] == UINT32_MAX) label[r] = count++;
    chart_of_triangle[t] = label[r];
  }
  return count;
}

DenoiseGuides build_denoise_guides(const scene::Scene& scene, const atlas::Atlas& atlas,
                                   const atlas::SampleInfo& info) {
  DenoiseGuides g;
  g.width = info.width;
  g.height = info.height;
  const size_t texels = size_t(info.width) * size_t(info.height);
  g.position.assign(texels, cl::float4{0, 0, 0, 0});
  g.normal.assign(texels, cl::float4{0, 0, 1, 0});
  g.chart.assign(texels, UINT32_MAX);

  // Charts per mesh, numbered per instance.
  std::vector<std::vector<uint32_t>> mesh_charts(scene.meshes.size());
  std::vector<uint32_t> mesh_chart_count(scene.meshes.size(), 0);
  std::vector<bool> labelled(scene.meshes.size(), false);
  std::vector<uint32_t> instance_base(scene.instances.size(), 0);
  uint32_t next = 0;
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    const size_t m = static_cast<size_t>(scene.instances[i].mesh);
    if (!labelled[m]) {
      mesh_chart_count[m] = label_uv_charts(scene.meshes[m], mesh_charts[m]);
      labelled[m] = true;
    }
    instance_base[i] = next;
    next += mesh_chart_count[m];
  }

  for (const uint32_t texel : info.covered_texels) {
    const uint32_t valid = cl::lux_sample_info_count(info.words.data(), info.offsets[texel]);
    const uint32_t n = std::min(valid, kGuideSamples);
    // Ranks spread over the texel's valid positions (ascending Hammersley
    // index; index 0 is the texel's corner, on a neighbour's triangle too).
    atlas::SamplePoint sp[kGuideSamples];
    uint32_t chart[kGuideSamples];
    for (uint32_t s = 0; s < n; ++s) {
      sp[s] = atlas::sample_point(info, texel, s * valid / n);
      chart[s] = instance_base[sp[s].instance] +
                 mesh_charts[size_t(scene.instances[sp[s].instance].mesh)][sp[s].triangle];
    }
    // The texel's chart: the one most of these samples lie on (the first
    // such on a tie). A texel straddling a chart border then joins one side
    // and its guides describe that side only.
    uint32_t best = chart[0], best_count = 0;
    for (uint32_t s = 0; s < n; ++s) {
      const auto count = static_cast<uint32_t>(std::count(chart, chart + n, chart[s]));
      if (count > best_count) best = chart[s], best_count = count;
    }
    g.chart[texel] = best;
    double p[3] = {0, 0, 0}, nrm[3] = {0, 0, 0}, side = 0;
    for (uint32_t s = 0; s < n; ++s) {
      if (chart[s] != best) continue;
      const scene::Instance& inst = scene.instances[sp[s].instance];
      const scene::Mesh& mesh = scene.meshes[size_t(inst.mesh)];
      const atlas::TexelTriangle tt =
          atlas::texel_triangle(scene, atlas, sp[s].instance, sp[s].triangle);
      const Vec3 b = atlas::atlas_barycentrics(tt, sp[s].x, sp[s].y);
      Vec3 v[3], vn{0, 0, 0};
      for (int k = 0; k < 3; ++k) {
        const uint32_t idx = mesh.indices[size_t{sp[s].triangle} * 3 + size_t(k)];
        v[k] = transform_point(inst.object_to_world, mesh.positions[idx]);
        const float w = k == 0 ? b.x : (k == 1 ? b.y : b.z);
        vn = vn + w * transform_normal(inst.object_to_world, mesh.normals[idx]);
      }
      const Vec3 x = b.x * v[0] + b.y * v[1] + b.z * v[2];
      vn = normalize(vn);
      p[0] += x.x, p[1] += x.y, p[2] += x.z;
      nrm[0] += vn.x, nrm[1] += vn.y, nrm[2] += vn.z;
      const double world_area = 0.5 * double(length(cross(v[1] - v[0], v[2] - v[0])));
      const double texel_area = 0.5 * std::abs((tt.x[1] - tt.x[0]) * (tt.y[2] - tt.y[0]) -
                                               (tt.y[1] - tt.y[0]) * (tt.x[2] - tt.x[0]));
      side += texel_area > 0 ? std::sqrt(world_area / texel_area) : 0.0;
    }
    const double m = best_count;
    const Vec3 mean_n = normalize(Vec3{float(nrm[0]), float(nrm[1]), float(nrm[2])});
    // A texel on zero-UV-area triangles only has no size: give it a tiny
    // one so it stays covered (it then mixes with coplanar neighbours only).
    const float w = std::max(static_cast<float>(side / m), 1e-30f);
    g.position[texel] = {float(p[0] / m), float(p[1] / m), float(p[2] / m), w};
    g.normal[texel] = {mean_n.x, mean_n.y, mean_n.z, 0};
  }
  return g;
}

}  // namespace luxel::pipeline
