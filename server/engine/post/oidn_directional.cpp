// Open Image Denoise on spherical-harmonic lightmaps (oidn.h run_sh): the
// RTLightmap filter's directional mode, as the OIDN API documentation
// describes it ("directional: the input contains normalized coefficients, in
// [-1, 1], of a directional lightmap, e.g. normalized L1 or higher order SH
// bands when L0 is stored separately"). L0 is radiance-like and filtered as
// HDR; every higher coefficient is divided by L0 and by its bound, filtered,
// and multiplied back by the filtered L0, so the filter sees the shape of the
// light's directional distribution apart from its brightness.
#include <algorithm>
#include <cmath>

#include "post/denoise.h"
#include "post/oidn.h"

namespace luxel::pipeline {
namespace {

// The normalised bands' blend towards their raw values, per channel: as
// OidnBlend::kShrink (oidn.cpp shrink_to_noise) with `sigma` the standard
// error of a normalised value, or within clamp_standard_errors x sigma.
void blend_plane(const std::vector<float>& raw, const std::vector<float>& sigma,
                 const std::vector<float>& rgba, const std::vector<uint32_t>& chart, int width,
                 int height, const OidnParams& params, std::vector<float>& out) {
  if (params.blend == OidnBlend::kNone) return;
  const std::vector<float> filtered = out;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const size_t t = size_t(y) * size_t(width) + size_t(x);
      if (!(rgba[t * 4 + 3] > 0.0f)) continue;
      for (size_t k = 0; k < 3; ++k) {
        const float r = raw[t * 3 + k];
        if (params.blend == OidnBlend::kClamp) {
          const float bound = params.clamp_standard_errors * sigma[t];
          out[t * 3 + k] = std::clamp(filtered[t * 3 + k], r - bound, r + bound);
          continue;
        }
        double s2 = 0, change = 0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int qx = x + dx, qy = y + dy;
            if (qx < 0 || qy < 0 || qx >= width || qy >= height) continue;
            const size_t q = size_t(qy) * size_t(width) + size_t(qx);
            if (!(rgba[q * 4 + 3] > 0.0f) || chart[q] != chart[t]) continue;
            const double d = double(filtered[q * 3 + k]) - double(raw[q * 3 + k]);
            s2 += double(sigma[q]) * double(sigma[q]);
            change += d * d;
          }
        const double w = change > s2 ? s2 / change : 1.0;
        out[t * 3 + k] = r + float(w) * (filtered[t * 3 + k] - r);
      }
    }
}

}  // namespace

Result<std::vector<float>> OidnDenoiser::run_sh(const std::vector<float>& coefficients, int count,
                                                const std::vector<float>& rgba,
                                                const std::vector<float>& rel_error,
                                                const std::vector<float>& band_bounds,
                                                const OidnParams& params) {
  const int width = guides_.width, height = guides_.height;
  const size_t texels = size_t(width) * size_t(height), n = size_t(count);
  if (count < 1 || coefficients.size() != texels * n * 3 || rgba.size() != texels * 4 ||
      rel_error.size() != texels || band_bounds.size() != n)
    return internal_error("oidn: directional input does not match the lightmap size");
  auto at = [&](size_t t, size_t i, size_t k) { return t * n * 3 + i * 3 + k; };

  // L0: HDR, then the irradiance map's blend with the variance of L0's
  // luminance from the texel's relative standard error.
  std::vector<float> l0_raw(texels * 4, 0.0f), l0_variance(texels, 0.0f);
  for (size_t t = 0; t < texels; ++t) {
    for (size_t k = 0; k < 3; ++k) l0_raw[t * 4 + k] = coefficients[at(t, 0, k)];
    l0_raw[t * 4 + 3] = rgba[t * 4 + 3];
    const double lum =
        0.2126 * l0_raw[t * 4] + 0.7152 * l0_raw[t * 4 + 1] + 0.0722 * l0_raw[t * 4 + 2];
    const double se = double(rel_error[t]) * lum;
    l0_variance[t] = std::isfinite(se) ? float(se * se) : 0.0f;
  }
  std::vector<float> plane(texels * 3);
  for (size_t t = 0; t < texels; ++t)
    for (size_t k = 0; k < 3; ++k) plane[t * 3 + k] = l0_raw[t * 4 + k];
  LUXEL_RETURN_IF_ERROR(filter_charts(plane, rgba, /*directional=*/false, params.whole_pages));
  std::vector<float> l0 = l0_raw;
  for (size_t t = 0; t < texels; ++t)
    if (rgba[t * 4 + 3] > 0.0f)
      for (size_t k = 0; k < 3; ++k) l0[t * 4 + k] = std::max(plane[t * 3 + k], 0.0f);
  blend(l0_raw, l0_variance, params, l0);

  std::vector<float> out = coefficients;
  for (size_t t = 0; t < texels; ++t)
    if (rgba[t * 4 + 3] > 0.0f)
      for (size_t k = 0; k < 3; ++k) out[at(t, 0, k)] = l0[t * 4 + k];

  // Higher coefficients, normalised by L0 and their bound. The normalised
  // value's standard error is taken as the texel's relative standard error
  // (a coefficient's noise scales with L0 like the irradiance's does).
  std::vector<float> sigma(texels, 0.0f);
  for (size_t t = 0; t < texels; ++t)
    sigma[t] = std::isfinite(rel_error[t]) ? std::max(rel_error[t], 0.0f) : 0.0f;
  for (size_t i = 1; i < n; ++i) {
    const float bound = band_bounds[i] > 0.0f ? band_bounds[i] : 1.0f;
    for (size_t t = 0; t < texels; ++t)
      for (size_t k = 0; k < 3; ++k) {
        const float base = l0_raw[t * 4 + k];
        plane[t * 3 + k] = base > 0.0f ? coefficients[at(t, i, k)] / (bound * base) : 0.0f;
      }
    const std::vector<float> normalised = plane;
    LUXEL_RETURN_IF_ERROR(filter_charts(plane, rgba, /*directional=*/true, params.whole_pages));
    blend_plane(normalised, sigma, rgba, guides_.chart, width, height, params, plane);
    for (size_t t = 0; t < texels; ++t) {
      if (!(rgba[t * 4 + 3] > 0.0f)) continue;
      for (size_t k = 0; k < 3; ++k)
        // Where L0 is 0 (no light) the raw coefficient is kept.
        out[at(t, i, k)] = l0_raw[t * 4 + k] > 0.0f ? plane[t * 3 + k] * bound * l0[t * 4 + k]
                                                    : coefficients[at(t, i, k)];
    }
  }
  return out;
}

}  // namespace luxel::pipeline
