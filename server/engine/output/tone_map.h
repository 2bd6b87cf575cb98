// The display transform of lightmap previews: exposure, Reinhard tone curve
// on luminance, sRGB encoding. Previews are for people; the EXR keeps the data.
//
//   scaled   = rgb * k                       (k: exposure scale, preview.h)
//   L        = 0.2126 R + 0.7152 G + 0.0722 B (Rec. 709 / sRGB luminance of scaled)
//   display  = clamp(scaled / (1 + L), 0, 1)  (Reinhard 2002, eq. 3, applied to
//                                              luminance so hue is kept; very
//                                              bright saturated colours clip)
//   encoded  = sRGB OETF(display), 8 bits     (IEC 61966-2-1)
//
// The curve is monotonic: a brighter grey never maps to a darker one.
#pragma once

#include <array>
#include <cstdint>

namespace luxel::output {

// Linear RGB value made safe to display: NaN and negatives become 0, +Inf
// becomes the largest float (displays as white).
double display_safe(float v);

double rec709_luminance(double r, double g, double b);

// Linear display RGB in [0,1] for linear scene RGB times exposure scale `k`.
std::array<double, 3> reinhard_luminance(double r, double g, double b, double k);

// sRGB opto-electronic transfer function, [0,1] -> [0,1].
double srgb_oetf(double linear);

// Rounds a [0,1] value to 8 bits (values outside are clamped).
uint8_t quantize_u8(double v);

}  // namespace luxel::output
