#include "output/tone_map.h"

#include <algorithm>
#include <cfloat>
#include <cmath>

namespace luxel::output {

double display_safe(float v) {
  if (std::isnan(v) || v <= 0.0f) return 0.0;
  if (std::isinf(v)) return FLT_MAX;
  return v;
}

double rec709_luminance(double r, double g, double b) {
  return 0.2126 * r + 0.7152 * g + 0.0722 * b;
}

std::array<double, 3> reinhard_luminance(double r, double g, double b, double k) {
  r *= k, g *= k, b *= k;
  const double scale = 1.0 / (1.0 + rec709_luminance(r, g, b));
  return {std::clamp(r * scale, 0.0, 1.0), std::clamp(g * scale, 0.0, 1.0),
          std::clamp(b * scale, 0.0, 1.0)};
}

double srgb_oetf(double linear) {
  linear = std::clamp(linear, 0.0, 1.0);
  return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}

uint8_t quantize_u8(double v) {
  return static_cast<uint8_t>(std::lround(std::clamp(v, 0.0, 1.0) * 255.0));
}

}  // namespace luxel::output
