// The Baker's denoiser (post/denoise.h): snapshots' previews and the final
// denoised lightmap, with the variance guide of bake/progressive_variance.h.
// `denoise = oidn` runs Open Image Denoise (post/oidn.h) when its library
// loads and the a-trous filter otherwise, saying why in the manifest.
#include <algorithm>
#include <nlohmann/json.hpp>

#include "bake/baker.h"

namespace luxel::pipeline {

Result<std::vector<float>> Baker::denoise(const std::vector<float>& rgba,
                                          const std::vector<float>& variance,
                                          size_t two_point_texels) {
  if (use_oidn()) {
    OidnParams p;
    p.variance_source = denoise_params(two_point_texels).variance_source;
    return oidn_->run(rgba, variance, p);
  }
  if (!denoiser_) {
    auto d = Denoiser::create(ctx_, build_denoise_guides(scene_, s_.atlas, s_.info));
    if (!d) return d.status();
    denoiser_ = std::move(d.value());
  }
  return denoiser_->run(rgba, variance, denoise_params(two_point_texels));
}

bool Baker::use_oidn() {
  if (settings_.denoise != Denoise::kOidn) return false;
  if (!oidn_tried_) {
    oidn_tried_ = true;
    auto lib = load_oidn();
    if (lib)
      oidn_ = std::make_unique<OidnDenoiser>(
          *lib.value(), build_denoise_guides(scene_, s_.atlas, s_.info), s_.atlas.pages);
    else
      oidn_missing_ = "not found: " + lib.status().message();
  }
  return oidn_ != nullptr;
}

std::string Baker::denoise_json(size_t two_point_texels) const {
  const DenoiseParams p = denoise_params(two_point_texels);
  if (oidn_) {
    OidnParams o;
    o.variance_source = p.variance_source;
    return oidn_->describe_json(o);
  }
  if (settings_.denoise != Denoise::kOidn) return p.describe_json();
  nlohmann::json j = nlohmann::json::parse(p.describe_json());
  j["oidn"] = oidn_missing_;
  return j.dump();
}

DenoiseParams Baker::denoise_params(size_t two_point_texels) const {
  DenoiseParams p;
  if (tracks_progressive_variance())
    p.variance_source = strprintf(
        "two-point progressive estimate (y_n - y_s)^2 s / (n - s) for %zu of %zu covered texels "
        "(bake/progressive_variance.h), Welford for the rest",
        two_point_texels, s_.info.covered_texels.size());
  return p;
}

Result<size_t> Baker::denoise_result() {
  BakeResult& result = result_;
  // The path buffers and sort/compaction scratch are done with: free them,
  // so the denoiser's buffers take their place within the budget.
  { BakeBuffers released = std::move(b_); }
  sort_.reset();
  compaction_.reset();
  offset_buffer_.reset();
  const size_t texels = size_t(s_.atlas.width) * size_t(s_.atlas.height);
  const size_t after = s_.tracer->device_bytes() + texels * Denoiser::kBytesPerTexel;
  // OIDN filters on the host: only the a-trous buffers count on the device.
  if (!use_oidn() && !denoiser_ && after > budget_) {
    result.denoise_json = strprintf(
        R"({"method":"atrous","skipped":"the denoiser needs %zu bytes beside the BVH, over the device-memory budget of %zu"})",
        after, budget_);
    return size_t{0};
  }
  const auto t_denoise = SteadyClock::now();
  std::unique_lock<std::mutex> turn;
  if (hooks_->device_turn) turn = std::unique_lock<std::mutex>(*hooks_->device_turn);
  size_t two_point = 0;
  const std::vector<float> variance =
      atlas_variance(result.irradiance, result.rel_error, nullptr, 0, &two_point);
  auto filtered = denoise(result.irradiance, variance, two_point);
  if (!filtered) return filtered.status();
  result.irradiance_denoised = std::move(filtered.value());
  result.denoise_variance = variance;
  result.denoise_json = denoise_json(two_point);
  result.denoise_s = seconds_since(t_denoise);
  return s_.tracer->device_bytes() + (denoiser_ ? denoiser_->device_bytes() : 0);
}

}  // namespace luxel::pipeline
