#include "output/preview.h"

#include <algorithm>
#include <cmath>

#include "common/atomic_file.h"
#include "output/oiio_codec.h"
#include "output/tone_map.h"

namespace luxel::output {
namespace {

struct Rgba {
  double r, g, b, a;
};

Status check_preview_input(const Image& image, const std::string& what) {
  LUXEL_RETURN_IF_ERROR(check_image(image, what));
  if (image.channels != 1 && image.channels != 3 && image.channels != 4)
    return invalid_argument(
        strprintf("%s: a preview needs 1, 3 or 4 channels, got %d", what.c_str(), image.channels));
  return Status::ok();
}

// Texel i as display-safe linear RGB plus coverage (1 without an alpha channel).
Rgba texel(const Image& image, size_t i) {
  const float* p = &image.pixels[i * static_cast<size_t>(image.channels)];
  if (image.channels == 1) {
    const double v = display_safe(p[0]);
    return {v, v, v, 1.0};
  }
  // Coverage is a fraction; NaN counts as uncovered.
  const double a = image.channels == 4 ? (p[3] > 0.0f ? std::min(1.0, double{p[3]}) : 0.0) : 1.0;
  return {display_safe(p[0]), display_safe(p[1]), display_safe(p[2]), a};
}

// Tone-maps every texel to 8-bit sRGB RGBA and encodes it as PNG.
Result<std::vector<uint8_t>> encode_png(const Image& image, double k, const std::string& what) {
  std::vector<uint8_t> rgba8(image.texel_count() * 4);
  for (size_t i = 0; i < image.texel_count(); ++i) {
    const Rgba t = texel(image, i);
    const auto display = reinhard_luminance(t.r, t.g, t.b, k);
    for (int c = 0; c < 3; ++c) rgba8[i * 4 + c] = quantize_u8(srgb_oetf(display[c]));
    rgba8[i * 4 + 3] = t.a > 0.0 ? 255 : 0;
  }
  OIIO::ImageSpec spec(image.width, image.height, 4, OIIO::TypeDesc::UINT8);
  spec.alpha_channel = 3;
  // Our alpha is a coverage mask, not premultiplication: stop OpenImageIO
  // from dividing RGB by it on write.
  spec.attribute("oiio:UnassociatedAlpha", 1);
  spec.attribute("oiio:ColorSpace", "sRGB");
  return encode_with_oiio("png", spec, OIIO::TypeDesc::UINT8, rgba8.data(), what);
}

}  // namespace

double preview_exposure_scale(const Image& image, const PreviewOptions& options) {
  const double compensation = std::exp2(static_cast<double>(options.exposure));
  double k = std::isfinite(compensation) && compensation > 0.0 ? compensation : 1.0;
  if (!options.auto_exposure || !check_preview_input(image, "preview").is_ok()) return k;
  std::vector<double> lum;
  lum.reserve(image.texel_count());
  for (size_t i = 0; i < image.texel_count(); ++i) {
    const Rgba t = texel(image, i);
    if (t.a > 0.0) lum.push_back(rec709_luminance(t.r, t.g, t.b));
  }
  if (lum.empty()) return k;
  const auto p95 =
      lum.begin() + static_cast<std::ptrdiff_t>(0.95 * static_cast<double>(lum.size() - 1));
  std::nth_element(lum.begin(), p95, lum.end());
  // 4 / (1 + 4) = 0.8 on the Reinhard curve (tone_map.h).
  const double automatic = *p95 > 0.0 ? 4.0 / *p95 : 1.0;
  const double scaled = k * automatic;
  return std::isfinite(scaled) && scaled > 0.0 ? scaled : automatic;
}

Status write_png_preview(const std::string& path, const Image& rgba,
                         const PreviewOptions& options) {
  if (path.empty()) return invalid_argument("write_png_preview: empty output path");
  LUXEL_RETURN_IF_ERROR(check_preview_input(rgba, path));
  auto png = encode_png(rgba, preview_exposure_scale(rgba, options), path);
  if (!png) return png.status();
  return write_file_atomic(path, png->data(), png->size());
}

Result<Image> downscale_box(const Image& rgba, int max_side) {
  LUXEL_RETURN_IF_ERROR(check_preview_input(rgba, "preview"));
  if (max_side <= 0)
    return invalid_argument(strprintf("preview: max_side %d must be positive", max_side));
  const int longest = std::max(rgba.width, rgba.height);
  const int side = std::min(longest, max_side);
  auto scaled = [&](int n) {
    return std::max(1, static_cast<int>(std::lround(static_cast<double>(n) * side / longest)));
  };
  Image out = make_image(scaled(rgba.width), scaled(rgba.height), 4);
  // Source ranges [x0, x1) partition the source: every texel counts once.
  auto range = [](int o, int src, int dst) {
    return std::pair<int, int>(static_cast<int>(int64_t{o} * src / dst),
                               static_cast<int>(int64_t{o + 1} * src / dst));
  };
  for (int oy = 0; oy < out.height; ++oy) {
    const auto [y0, y1] = range(oy, rgba.height, out.height);
    for (int ox = 0; ox < out.width; ++ox) {
      const auto [x0, x1] = range(ox, rgba.width, out.width);
      double sum[3] = {0, 0, 0}, weighted[3] = {0, 0, 0}, coverage = 0;
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
          const Rgba t = texel(rgba, static_cast<size_t>(y) * rgba.width + x);
          const double v[3] = {t.r, t.g, t.b};
          for (int c = 0; c < 3; ++c) sum[c] += v[c], weighted[c] += v[c] * t.a;
          coverage += t.a;
        }
      const double n = static_cast<double>(x1 - x0) * (y1 - y0);
      for (int c = 0; c < 3; ++c)
        out.at(ox, oy, c) =
            static_cast<float>(coverage > 0.0 ? weighted[c] / coverage : sum[c] / n);
      out.at(ox, oy, 3) = static_cast<float>(coverage / n);
    }
  }
  return out;
}

Result<std::vector<uint8_t>> encode_png_preview(const Image& rgba, int max_side,
                                                const PreviewOptions& options) {
  auto small = downscale_box(rgba, max_side);
  if (!small) return small.status();
  return encode_png(*small, preview_exposure_scale(rgba, options), "preview");
}

}  // namespace luxel::output
