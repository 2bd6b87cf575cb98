#include "probes/sh_window.h"

#include <cmath>

#include "kernels/shared/bases.h"

namespace luxel::probes {

const char* sh_window_name(ShWindow w) {
  switch (w) {
    case ShWindow::kNone:
      return "none";
    case ShWindow::kHanning:
      return "hanning";
    case ShWindow::kLanczos:
      return "lanczos";
  }
  return "?";
}

Result<ShWindow> parse_sh_window(const std::string& name) {
  if (name == "none") return ShWindow::kNone;
  if (name == "hanning") return ShWindow::kHanning;
  if (name == "lanczos") return ShWindow::kLanczos;
  return invalid_argument("settings.probe_window: '" + name +
                          "' is not one of none, hanning, lanczos");
}

std::array<float, 3> sh_window_sigma(ShWindow window, float width) {
  std::array<float, 3> s{1, 1, 1};
  for (int l = 1; l < 3; ++l) {
    const double x = M_PI * l / width;
    if (window == ShWindow::kHanning)
      s[l] = l >= width ? 0.0f : static_cast<float>((1 + std::cos(x)) / 2);
    else if (window == ShWindow::kLanczos)
      s[l] = static_cast<float>(std::sin(x) / x);
  }
  return s;
}

void sh_irradiance(const float* coeffs, int count, const std::array<float, 3>& sigma, float nx,
                   float ny, float nz, float out_rgb[3]) {
  float y[LUX_SH_L2_COUNT];
  lux_sh_eval(nx, ny, nz, count, y);
  out_rgb[0] = out_rgb[1] = out_rgb[2] = 0;
  for (int i = 0; i < count; ++i) {
    const int l = i == 0 ? 0 : (i < 4 ? 1 : 2);
    const float w = sigma[static_cast<size_t>(l)] * lux_sh_cosine_band(l) * y[i];
    for (int c = 0; c < 3; ++c) out_rgb[c] += w * coeffs[i * 3 + c];
  }
}

}  // namespace luxel::probes
