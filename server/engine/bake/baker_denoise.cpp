// The Baker's denoiser (post/denoise.h): snapshots' previews and the final
// denoised lightmap, with the variance guide of bake/progressive_variance.h.
// `denoise = oidn` runs Open Image Denoise (post/oidn.h) when its library
// loads and the a-trous filter otherwise, saying why in the manifest.
// `denoise = auto` (the default) runs OIDN when its library loads and leaves
// the map raw otherwise: measured at equal time, OIDN with the shrinkage
// blend lowered the RMSE by 20-45 % on interiors and courtyards and was
// within the measure's noise of the raw map where the sun dominates, while
// the a-trous filter was worse than the raw map on the foliage and sky
// courtyard scenes (docs/accuracy.md "Denoiser: the default").
#include <algorithm>
#include <nlohmann/json.hpp>

#include "bake/baker.h"
#include "common/cancel.h"
#include "encode/basis.h"

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

Denoise Baker::denoise_method() const {
  if (settings_.denoise != Denoise::kAuto) return settings_.denoise;
  // One shard's map holds part of the samples and is never delivered: only
  // the merge of all shards is (shards/shard_merge.h), and it denoises.
  if (settings_.sharded()) return Denoise::kOff;
  return load_oidn() ? Denoise::kOidn : Denoise::kOff;
}

std::string Baker::auto_off_json() const {
  auto lib = load_oidn();
  nlohmann::json j = {{"method", "off"},
                      {"auto",
                       "Open Image Denoise not found, so the map stays raw (auto never "
                       "picks the a-trous filter: docs/accuracy.md \"Denoiser: the "
                       "default\")"},
                      {"oidn", lib ? std::string() : "not found: " + lib.status().message()}};
  return j.dump();
}

bool Baker::use_oidn() {
  if (denoise_method() != Denoise::kOidn) return false;
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
    nlohmann::json j = nlohmann::json::parse(oidn_->describe_json(o));
    j["chosen_by"] = settings_.denoise == Denoise::kAuto ? "auto" : "the settings";
    return j.dump();
  }
  if (denoise_method() != Denoise::kOidn) return p.describe_json();
  nlohmann::json j = nlohmann::json::parse(p.describe_json());
  j["oidn"] = oidn_missing_;
  return j.dump();
}

namespace {

// max |Y_i| / Y_0 of each SH coefficient over the sphere, on a Fibonacci
// set of directions: a non-negative radiance's coefficient i is at most that
// times L0 in magnitude (the coefficient of a single direction w is Y_i(w),
// and Y_0 is constant), so the quotient lies in [-1, 1] as the filter's
// directional mode needs.
std::vector<float> sh_band_bounds(const encode::SphericalBasis& basis) {
  const int n = basis.size();
  std::vector<float> bound(static_cast<size_t>(n), 0.0f);
  std::vector<float> y(static_cast<size_t>(n), 0.0f);
  constexpr int kDirections = 8192;
  for (int d = 0; d < kDirections; ++d) {
    const double z = 1.0 - (2.0 * d + 1.0) / kDirections;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = d * 2.399963229728653;  // golden angle
    basis.evaluate(Vec3{float(r * std::cos(phi)), float(r * std::sin(phi)), float(z)}, y.data());
    for (int i = 0; i < n; ++i)
      bound[size_t(i)] = std::max(bound[size_t(i)], std::abs(y[size_t(i)]));
  }
  for (int i = n - 1; i >= 0; --i) bound[size_t(i)] /= bound[0];
  return bound;
}

}  // namespace

Result<std::string> Baker::denoise_sh_encodings(BakeResult& result) {
  std::vector<std::string> filtered, raw;
  for (EncodedLightmap& e : result.encodings) {
    auto basis = encode::SphericalBasis::from_name(e.name);
    const bool sh = basis && (basis.value().spec().kind == encode::BasisKind::kShL1 ||
                              basis.value().spec().kind == encode::BasisKind::kShL2);
    if (!sh) {
      raw.push_back(e.name);
      continue;
    }
    LUXEL_RETURN_IF_ERROR(check_cancel(
        CancelToken(hooks_->discard_cancelled ? hooks_->cancel : nullptr), "the denoise"));
    OidnParams p;
    auto out = oidn_->run_sh(e.coefficients, e.count, result.irradiance, result.rel_error,
                             sh_band_bounds(basis.value()), p);
    if (!out) return out.status();
    e.coefficients_denoised = std::move(out.value());
    filtered.push_back(e.name);
  }
  std::string says;
  auto list = [](const std::vector<std::string>& v) {
    std::string s;
    for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
    return s;
  };
  if (!filtered.empty())
    says = list(filtered) +
           ": L0 as HDR, higher bands divided by L0 and their bound in the directional mode, "
           "each value within one standard error of its raw one (<encoding>_denoised.exr)";
  if (!raw.empty())
    says += (says.empty() ? "" : "; ") + list(raw) +
            ": left raw (docs/accuracy.md \"Open Image Denoise\": scaling the lobes by the "
            "denoised irradiance lowered their error by 1-3 %)";
  return says.empty() ? std::string("no directional encodings") : says;
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
  // A host that throws a cancelled bake away (the daemon) stops between the
  // denoiser's steps: at 2048^2 each takes up to a second on a CPU, and the
  // device's turn may be another bake's for longer.
  const CancelToken cancel(hooks_->discard_cancelled ? hooks_->cancel : nullptr);
  std::unique_lock<std::mutex> turn;
  if (hooks_->device_turn) turn = std::unique_lock<std::mutex>(*hooks_->device_turn);
  LUXEL_RETURN_IF_ERROR(check_cancel(cancel, "the denoise"));
  size_t two_point = 0;
  const std::vector<float> variance =
      atlas_variance(result.irradiance, result.rel_error, nullptr, 0, &two_point);
  LUXEL_RETURN_IF_ERROR(check_cancel(cancel, "the denoise"));
  auto filtered = denoise(result.irradiance, variance, two_point);
  if (!filtered) return filtered.status();
  LUXEL_RETURN_IF_ERROR(check_cancel(cancel, "the denoise"));
  result.irradiance_denoised = std::move(filtered.value());
  result.denoise_variance = variance;
  nlohmann::json j = nlohmann::json::parse(denoise_json(two_point));
  if (oidn_) {
    auto directional = denoise_sh_encodings(result);
    if (!directional) return directional.status();
    j["directional"] = directional.value();
  }
  result.denoise_s = seconds_since(t_denoise);
  // All of it (variances, crops, filter, blend, directional encodings): what
  // the denoised map cost beside the trace, for benchmarks that charge it.
  j["seconds"] = result.denoise_s;
  result.denoise_json = j.dump();
  return s_.tracer->device_bytes() + (denoiser_ ? denoiser_->device_bytes() : 0);
}

}  // namespace luxel::pipeline
