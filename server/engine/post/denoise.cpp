#include "post/denoise.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "device/program_cache.h"
#include "kernels/shared/denoise.h"

namespace luxel::pipeline {

static_assert(sizeof(cl::LuxDenoiseParams) == 32 && alignof(cl::LuxDenoiseParams) == 4);

std::string DenoiseParams::describe_json() const {
  nlohmann::json j = {{"method", "atrous"},
                      {"reference",
                       "edge-avoiding a-trous wavelets (Dammertz et al. 2010), variance-guided "
                       "(SVGF, Schied et al. 2017)"},
                      {"iterations", iterations},
                      {"kernel", "5x5 B3 spline"},
                      {"sigma_luminance", sigma_luminance},
                      {"sigma_normal", sigma_normal},
                      {"sigma_plane_texels", sigma_plane},
                      {"guides", "world position, shading normal, chart id per texel"},
                      {"variance", variance_source},
                      {"clamp_standard_errors", clamp_standard_errors}};
  return j.dump();
}

std::vector<float> texel_variance(const std::vector<float>& rgba,
                                  const std::vector<float>& rel_error) {
  std::vector<float> v(rel_error.size(), 0.0f);
  for (size_t t = 0; t < v.size(); ++t) {
    const float* c = &rgba[t * 4];
    const float y = 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2];
    const float s = rel_error[t] * y;
    v[t] = s * s;
  }
  return v;
}

Result<std::unique_ptr<Denoiser>> Denoiser::create(device::Context& ctx,
                                                   const DenoiseGuides& guides) {
  std::unique_ptr<Denoiser> d(new Denoiser(ctx));
  d->width_ = guides.width;
  d->height_ = guides.height;
  const size_t texels = size_t(guides.width) * size_t(guides.height);
  if (guides.position.size() != texels || guides.normal.size() != texels ||
      guides.chart.size() != texels)
    return internal_error("denoiser: guides do not match the lightmap size");
  auto program = ctx.programs().get("denoise.cl", {});
  if (!program) return program.status();
  auto k = program.value()->kernel("denoise_atrous");
  if (!k) return k.status();
  d->atrous_ = std::move(k.value());
  auto up = [&](auto& data, const char* name, device::Buffer& out) -> Status {
    auto b = ctx.upload(data, name);
    if (!b) return b.status();
    out = std::move(b.value());
    return Status::ok();
  };
  LUXEL_RETURN_IF_ERROR(up(guides.position, "denoise guide position", d->position_));
  LUXEL_RETURN_IF_ERROR(up(guides.normal, "denoise guide normal", d->normal_));
  LUXEL_RETURN_IF_ERROR(up(guides.chart, "denoise guide chart", d->chart_ids_));
  d->chart_ = guides.chart;
  for (int i = 0; i < 2; ++i) {
    auto c = ctx.alloc(texels * sizeof(cl::float4), "denoise colour");
    if (!c) return c.status();
    d->color_[i] = std::move(c.value());
    auto v = ctx.alloc(texels * sizeof(float), "denoise variance");
    if (!v) return v.status();
    d->variance_[i] = std::move(v.value());
  }
  return d;
}

size_t Denoiser::device_bytes() const {
  return position_.bytes() + normal_.bytes() + chart_ids_.bytes() + one_chart_.bytes() +
         2 * (color_[0].bytes() + variance_[0].bytes());
}

Result<std::vector<float>> Denoiser::run(const std::vector<float>& rgba,
                                         const std::vector<float>& variance,
                                         const DenoiseParams& params) {
  const size_t texels = size_t(width_) * size_t(height_);
  if (rgba.size() != texels * 4 || variance.size() != texels)
    return internal_error("denoiser: input does not match the lightmap size");
  if (params.ignore_charts && !one_chart_) {
    auto b = ctx_.upload(std::vector<uint32_t>(texels, 0u), "denoise one chart");
    if (!b) return b.status();
    one_chart_ = std::move(b.value());
  }
  const device::Buffer& charts = params.ignore_charts ? one_chart_ : chart_ids_;
  LUXEL_RETURN_IF_ERROR(ctx_.write(color_[0], rgba.data(), texels * sizeof(cl::float4)));
  LUXEL_RETURN_IF_ERROR(ctx_.write(variance_[0], variance.data(), texels * sizeof(float)));
  int src = 0;
  for (int i = 0; i < params.iterations; ++i) {
    cl::LuxDenoiseParams p{};
    p.width = width_;
    p.height = height_;
    p.step = 1 << i;
    p.sigma_luminance = params.sigma_luminance;
    p.sigma_normal = params.sigma_normal;
    p.sigma_plane = params.sigma_plane;
    LUXEL_RETURN_IF_ERROR(atrous_.set_args(p, color_[src], variance_[src], color_[1 - src],
                                           variance_[1 - src], position_, normal_, charts));
    LUXEL_RETURN_IF_ERROR(ctx_.launch(atrous_, texels, 64, "denoise_atrous"));
    src = 1 - src;
  }
  std::vector<float> out(texels * 4);
  LUXEL_RETURN_IF_ERROR(ctx_.read(color_[src], out.data(), texels * sizeof(cl::float4)));
  LUXEL_RETURN_IF_ERROR(ctx_.finish());
  if (params.clamp_standard_errors > 0) clamp_to_raw(rgba, variance, params, out);
  return out;
}

void Denoiser::clamp_to_raw(const std::vector<float>& rgba, const std::vector<float>& variance,
                            const DenoiseParams& params, std::vector<float>& out) const {
  clamp_to_standard_errors(rgba, variance, chart_, width_, height_, params.clamp_standard_errors,
                           out);
}

void clamp_to_standard_errors(const std::vector<float>& rgba, const std::vector<float>& variance,
                              const std::vector<uint32_t>& chart, int width, int height,
                              float standard_errors, std::vector<float>& out) {
  auto lum = [](const float* c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; };
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const size_t t = size_t(y) * size_t(width) + size_t(x);
      if (!(rgba[t * 4 + 3] > 0.0f)) continue;
      // The variance smoothed over the covered 3x3 neighbours of the chart:
      // a two-point variance has one degree of freedom per texel.
      double sum = 0;
      int n = 0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int qx = x + dx, qy = y + dy;
          if (qx < 0 || qy < 0 || qx >= width || qy >= height) continue;
          const size_t q = size_t(qy) * size_t(width) + size_t(qx);
          if (!(rgba[q * 4 + 3] > 0.0f) || chart[q] != chart[t]) continue;
          sum += std::max(0.0f, variance[q]);
          ++n;
        }
      const double bound = standard_errors * std::sqrt(sum / std::max(n, 1));
      const double raw = lum(&rgba[t * 4]), filtered = lum(&out[t * 4]);
      const double moved = std::abs(filtered - raw);
      if (!(moved > bound)) continue;
      const float keep = static_cast<float>(bound / moved);  // of the filter's change
      for (int c = 0; c < 3; ++c)
        out[t * 4 + c] = rgba[t * 4 + c] + keep * (out[t * 4 + c] - rgba[t * 4 + c]);
    }
}

}  // namespace luxel::pipeline
