// The one-line progress bar of `luxel bake` (in-process and remote) and
// `luxel watch`: bar, percentage, samples per texel, error estimate, ETA.
#pragma once

#include <cstdint>
#include <string>

namespace luxel::cli {

struct ProgressView {
  double fraction = 0;  // 0..1 towards the nearest stopping rule
  double mean_spp = 0;  // mean samples per covered texel
  uint32_t min_spp = 0;
  double error = 0;      // mean relative standard error
  double elapsed_s = 0;  // seconds of tracing
  double eta_s = -1;     // seconds left, -1 unknown
  double rmse = -1;      // against a reference lightmap, -1 without one
  double rel_mse = -1;
};

// "42s", "3m05s", "1h02m"; "--" for a negative (unknown) duration.
std::string format_duration(double seconds);

// On a terminal the bar redraws in place (\r); otherwise one line per call.
// `label` (e.g. "RUNNING") is printed before the bar when non-empty.
void draw_progress_bar(const ProgressView& p, bool tty, const std::string& label = "");

}  // namespace luxel::cli
