// Runs the test kernels of kernels/testing/lights_probe.cl on the OpenCL
// device (PoCL in CI): one call of a shading device function per work-item.
#pragma once

#include <memory>
#include <vector>

#include "device/context.h"
#include "device/feature_set.h"
#include "device/program_cache.h"
#include "shading/light_table.h"
#include "shading/texture_pack.h"

namespace luxel::pipeline::test {

// Every light feature: one compiled program serves most tests (the sky kind
// is also switched at run time).
device::FeatureSet all_light_features();

struct LightSamples {
  std::vector<cl::float4> wi_pdf;         // wi, pdf (0: no sample)
  std::vector<cl::float4> radiance_dist;  // radiance, dist
  std::vector<cl::int4> info;             // light, triangle, is_delta | mis << 1, returned value
  std::vector<cl::float2> bary;

  bool ok(size_t i) const { return info[i].w != 0; }
  bool is_delta(size_t i) const { return (info[i].z & 1) != 0; }
  bool mis(size_t i) const { return (info[i].z & 2) != 0; }
};

class LightProbe {
 public:
  // Uploads the table and builds the probe program with `features`.
  static Result<std::unique_ptr<LightProbe>> create(
      const LightTable& table, const device::FeatureSet& features = all_light_features());

  // lux_sample_light at points[i] with normal normals[i] (empty: +Y) and
  // randoms[i] = (u_select, u.x, u.y, -).
  Result<LightSamples> sample(const std::vector<cl::float4>& points,
                              const std::vector<cl::float4>& randoms,
                              std::vector<cl::float4> normals = {});
  // The same point and normal for every sample.
  Result<LightSamples> sample_at(Vec3 p, const std::vector<cl::float4>& randoms,
                                 Vec3 n = {0, 1, 0});
  // lux_light_pdf_triangle per query.
  Result<std::vector<float>> triangle_pdf(const std::vector<int>& light,
                                          const std::vector<cl::float4>& p,
                                          const std::vector<cl::float4>& hit,
                                          const std::vector<cl::float4>& normal);
  // lux_sky_radiance (xyz) and lux_sky_pdf (w) along each direction, from a
  // point with normal n.
  Result<std::vector<cl::float4>> sky(const std::vector<cl::float4>& dirs, Vec3 n = {0, 1, 0});

 private:
  LightProbe() = default;
  const LightTable* table_ = nullptr;
  const device::Program* program_ = nullptr;
  device::Buffer lights_, cdf_, sky_texels_, sky_block_cdfs_, sky_texel_cdfs_;
};

// lux_sample_cdf(cdf, n, u[i]) -> (index, pmf).
Status probe_sample_cdf(const std::vector<float>& cdf, const std::vector<float>& u,
                        std::vector<int>* index, std::vector<float>* pmf);

// lux_sample_alias(table, n, u[i]) -> (index, pmf).
Status probe_sample_alias(const std::vector<cl::LuxAliasEntry>& table, const std::vector<float>& u,
                          std::vector<int>* index, std::vector<float>* pmf);

// lux_texture_sample(pack.textures[texture], uv[i]) (repeat, no transform).
Result<std::vector<cl::float4>> probe_texture(const TexturePack& pack, int texture,
                                              const std::vector<cl::float2>& uv);

// lux_texture_slot_sample(slot, uv0[i], uv1[i]): UV set, transform, wraps.
Result<std::vector<cl::float4>> probe_texture_slot(const TexturePack& pack,
                                                   const cl::LuxTextureSlot& slot,
                                                   const std::vector<cl::float2>& uv0,
                                                   const std::vector<cl::float2>& uv1);

}  // namespace luxel::pipeline::test
