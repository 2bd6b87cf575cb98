#include "progress_bar.h"

#include <algorithm>
#include <cstdio>

#include "common/status.h"

namespace luxel::cli {

std::string format_duration(double s) {
  if (s < 0) return "--";
  if (s < 60) return strprintf("%.0fs", s);
  if (s < 3600) return strprintf("%dm%02ds", int(s) / 60, int(s) % 60);
  return strprintf("%dh%02dm", int(s) / 3600, (int(s) / 60) % 60);
}

void draw_progress_bar(const ProgressView& p, bool tty, const std::string& label) {
  const int width = 30;
  const double fraction = std::clamp(p.fraction, 0.0, 1.0);
  const int filled = static_cast<int>(fraction * width + 0.5);
  std::string bar(static_cast<size_t>(filled), '#');
  bar.resize(width, '.');
  const std::string vs_reference =
      p.rmse >= 0 ? strprintf("  rmse %.4g relmse %.3g", p.rmse, p.rel_mse) : std::string();
  std::fprintf(stdout, "%s%s%s[%s] %5.1f%%  spp %.1f (min %u)  error %.4f%s  %s elapsed  ETA %s%s",
               tty ? "\r" : "", label.c_str(), label.empty() ? "" : " ", bar.c_str(),
               100.0 * fraction, p.mean_spp, p.min_spp, p.error, vs_reference.c_str(),
               format_duration(p.elapsed_s).c_str(), format_duration(p.eta_s).c_str(),
               tty ? "   " : "\n");
  std::fflush(stdout);
}

}  // namespace luxel::cli
