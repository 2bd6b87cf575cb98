// Ringing control for SH irradiance (Sloan, "Stupid Spherical Harmonics
// (SH) Tricks", GDC 2008, §"Windowing"): band l of the coefficients is
// scaled by sigma_l before the clamped-cosine convolution, so a bright small
// source does not drive the reconstructed irradiance negative on the far
// side. Windows of width w (Sloan's convention; w = L + 1 for order L):
//   hanning:  sigma_l = (1 + cos(pi l / w)) / 2
//   lanczos:  sigma_l = sinc(l / w) = sin(pi l / w) / (pi l / w)
//   none:     sigma_l = 1 (the raw projection)
// The window is applied at evaluation (SDK) and recorded in the probe files;
// the stored coefficients are the raw projection.
#pragma once

#include <array>
#include <string>

#include "common/status.h"

namespace luxel::probes {

enum class ShWindow { kNone, kHanning, kLanczos };
const char* sh_window_name(ShWindow w);  // "none", "hanning", "lanczos"
Result<ShWindow> parse_sh_window(
    const std::string& name);  // INVALID_ARGUMENT names settings.probe_window

// sigma_0..sigma_2 for a window of width w (w > 0).
std::array<float, 3> sh_window_sigma(ShWindow window, float width);

// Irradiance about unit normal n from 3-channel SH radiance coefficients
// (count 4 or 9, coefficient-major RGB; kernels/shared/bases.h order and
// normalisation): E = sum_lm sigma_l A_l c_lm Y_lm(n).
void sh_irradiance(const float* coeffs, int count, const std::array<float, 3>& sigma, float nx,
                   float ny, float nz, float out_rgb[3]);

}  // namespace luxel::probes
