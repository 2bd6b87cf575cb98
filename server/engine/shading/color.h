// Colour helpers shared by the light table and the texture packer (host).
#pragma once

#include <algorithm>
#include <cmath>

#include "common/math.h"

namespace luxel::pipeline {

// Rec. 709 / sRGB-primaries luminance of linear RGB: the one scalar used to
// weigh lights by power (thesis §6.3.2) and sky texels by brightness.
inline double luminance(Vec3 c) {
  return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
}

// The exact sRGB OETF (IEC 61966-2-1), linear [0,1] -> encoded [0,1].
inline float linear_to_srgb(float v) {
  v = std::clamp(v, 0.0f, 1.0f);
  return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

// Its inverse, encoded [0,1] -> linear [0,1].
inline float srgb_to_linear(float e) {
  e = std::clamp(e, 0.0f, 1.0f);
  return e <= 0.04045f ? e / 12.92f : std::pow((e + 0.055f) / 1.055f, 2.4f);
}

}  // namespace luxel::pipeline
