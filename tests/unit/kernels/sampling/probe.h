// Host side of kernels/testing/sampling_probe.cl: runs the device sampling
// functions for batches of inputs on the real OpenCL device (PoCL in CI).
//
// Two builds of the probe program are used:
//   kSobolSpecular      LUX_SPECULAR: Owen-scrambled Sobol sequences and the
//                       full two-layer BSDF;
//   kRandomDiffuseOnly  LUX_SEQUENCE_RANDOM, no LUX_SPECULAR: the random
//                       sequence ablation and the diffuse-only BSDF.
// Pairing the two switches keeps it to two program builds (PoCL compiles
// take seconds); the switches touch disjoint headers.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "common/status.h"
#include "device/context.h"
#include "kernels/shared/compat.h"

namespace luxel::sampling_test {

using cl::float2;
using cl::float4;
using cl::uint4;

enum class Build { kSobolSpecular, kRandomDiffuseOnly };

// Warp selector of probe_warp.
enum class Warp : int {
  kCosineHemisphere = 0,
  kUniformHemisphere = 1,
  kUniformSphere = 2,
  kUniformCone = 3,
  kUniformTriangle = 4
};

struct Material {
  float4 base_metallic;  // base colour rgb, metallic
  float roughness;
  float dielectric_f0 = 0.04f;  // ((ior - 1) / (ior + 1))^2; passed in wo.w
  // KHR_materials_specular: dielectric (f0 rgb, f90); w = 0: f0 above, f90 1.
  float4 specular = {0, 0, 0, 0};
};

struct BsdfSamples {
  std::vector<float4> sample;  // (wi, layer)
  std::vector<float4> weight;  // (weight, pdf)
  std::vector<float4> check;   // (f_layer cos / pdf, lux_bsdf_pdf_layer of the layer)
};

class Probe {
 public:
  // The largest batch of device-side uniforms (see uniforms()).
  static constexpr size_t kMaxSamples = size_t(1) << 20;

  // The process-wide probe: OpenCL start-up, program builds and the uniform
  // buffer are paid once per test executable.
  static Result<Probe*> instance();

  // kMaxSamples float4 of independent uniform [0,1) numbers from a host
  // generator (std::mt19937_64), also resident on the device; sampling probes
  // consume the first `count` of them.
  const std::vector<float4>& uniforms() const { return uniforms_; }

  Result<std::vector<float2>> sequence(Build build, const std::vector<uint4>& queries);
  Result<std::vector<uint32_t>> hash(const std::vector<uint32_t>& in);
  // lux_sobol_dim1 of every input (Sobol dimension 1 before scrambling).
  Result<std::vector<uint32_t>> sobol_dim1(const std::vector<uint32_t>& in);
  Result<std::vector<float4>> warp(Warp warp, float param, size_t count);
  Result<std::vector<float>> cosine_hemisphere_pdf(const std::vector<float4>& dirs);
  Result<std::vector<float4>> onb(const std::vector<float4>& normals,
                                  const std::vector<float4>& vectors);
  // roughness[i] = (roughness, wo.z or 0 for 1, -, -); three float4 per
  // material: (diffuse, alpha), (f0, p_specular), (ms, p_cosine).
  Result<std::vector<float4>> make_bsdf(Build build, const std::vector<float4>& base_metallic,
                                        const std::vector<float4>& roughness);
  // u_layer_override < 0: the layer is chosen with the uniforms' z.
  Result<BsdfSamples> bsdf_sample(Build build, const Material& m, float4 wo, float u_layer_override,
                                  size_t count);
  Result<std::vector<float4>> bsdf_eval(Build build, const Material& m, float4 wo,
                                        const std::vector<float4>& dirs);

 private:
  Probe() = default;
  Status init();
  Result<device::Kernel> kernel(Build build, const char* name);
  // Runs a uint -> uint probe kernel (in, count, out) over the values.
  Result<std::vector<uint32_t>> u32_function(const char* name, const std::vector<uint32_t>& values);
  template <typename T>
  Result<std::vector<T>> read_back(const device::Buffer& buffer, size_t count);

  std::unique_ptr<device::Context> ctx_;
  std::vector<float4> uniforms_;
  device::Buffer uniforms_device_;
};

}  // namespace luxel::sampling_test
