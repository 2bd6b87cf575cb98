// Edge-avoiding a-trous denoiser of a baked lightmap (kernels/denoise.cl):
// Dammertz et al. 2010 with the variance-guided luminance weight of SVGF
// (Schied et al. 2017), over the texel domain, guided by per-texel world
// position, shading normal and chart id (denoise_guides.h).
//
//   auto d = Denoiser::create(ctx, guides);          // uploads the guides once
//   auto out = d.value()->run(rgba, variance, params);
//
// The raw lightmap stays the bake's result; the filtered one is an extra
// output (irradiance_denoised.exr). Deterministic like the bake: the same
// input and device give the same bits.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "common/status.h"
#include "device/context.h"
#include "post/denoise_guides.h"

namespace luxel::pipeline {

struct DenoiseParams {
  int iterations = 5;            // tap spacing 1, 2, 4, 8, 16 texels
  float sigma_luminance = 2.0f;  // SVGF sigma_l (their 4): luminance edge-stop, in standard errors
  float sigma_normal = 128.0f;   // SVGF sigma_n: exponent of max(0, n.n')
  float sigma_plane = 1.0f;      // tangent-plane distance edge-stop, in texels
  // Test hook (the injected error of the edge test): treat all texels as one
  // chart. Never set by a bake.
  bool ignore_charts = false;
  // After filtering, each texel's luminance stays within this many standard
  // errors of its raw value (the variance smoothed over its 3x3 chart
  // neighbours; the colour is scaled towards the raw one). The filter's bias
  // then shrinks with the noise, so the denoised map converges to the raw one;
  // 0 turns the clamp off. Needs a variance that is not overstated: with the
  // Welford variance of stratified samples it bounded nothing
  // (docs/accuracy.md "Denoiser").
  float clamp_standard_errors = 1.0f;
  // What the variances given to run() are, for the manifest (set by the bake).
  std::string variance_source = "Welford variance of each texel's samples";

  // {"method":"atrous","iterations":5,...} for the manifest.
  std::string describe_json() const;
};

// Variance of each texel's luminance mean from the bake's per-texel
// relative standard error (BakeResult::rel_error) and its RGBA mean:
// (rel_error * luminance)^2.
std::vector<float> texel_variance(const std::vector<float>& rgba,
                                  const std::vector<float>& rel_error);

// The blend after filtering (DenoiseParams::clamp_standard_errors, shared by
// the a-trous and OIDN filters): each covered texel's luminance in `out` is
// held within `standard_errors` standard errors of its raw value in `rgba`
// (the variance averaged over its covered 3x3 neighbours on the same chart),
// scaling the filter's change of all three channels. Uncovered texels and
// alpha are left alone.
void clamp_to_standard_errors(const std::vector<float>& rgba, const std::vector<float>& variance,
                              const std::vector<uint32_t>& chart, int width, int height,
                              float standard_errors, std::vector<float>& out);

class Denoiser {
 public:
  static Result<std::unique_ptr<Denoiser>> create(device::Context& ctx,
                                                  const DenoiseGuides& guides);

  // `rgba`: width * height RGBA texels (A = coverage, passed through);
  // `variance`: width * height variances of the texel means' luminance.
  // Returns the filtered RGBA; uncovered texels unchanged.
  Result<std::vector<float>> run(const std::vector<float>& rgba, const std::vector<float>& variance,
                                 const DenoiseParams& params);

  size_t device_bytes() const;
  // Device bytes per texel: guides (position, normal, chart) and two
  // colour + variance buffers.
  static constexpr size_t kBytesPerTexel = 16 + 16 + 4 + 2 * (16 + 4);

 private:
  explicit Denoiser(device::Context& ctx) : ctx_(ctx) {}
  // clamp_to_standard_errors on the filtered `out`.
  void clamp_to_raw(const std::vector<float>& rgba, const std::vector<float>& variance,
                    const DenoiseParams& params, std::vector<float>& out) const;
  device::Context& ctx_;
  int width_ = 0, height_ = 0;
  device::Kernel atrous_;
  device::Buffer position_, normal_, chart_ids_, one_chart_;
  device::Buffer color_[2], variance_[2];
  std::vector<uint32_t> chart_;  // host copy of the chart guide, for the clamp
};

}  // namespace luxel::pipeline
