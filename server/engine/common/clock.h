// Wall-clock intervals for reports and schedules (never for results: a
// bake's bits do not depend on time).
#pragma once

#include <chrono>

namespace luxel {

using SteadyClock = std::chrono::steady_clock;

// Seconds from t0 to now on the steady clock.
inline double seconds_since(SteadyClock::time_point t0) {
  return std::chrono::duration<double>(SteadyClock::now() - t0).count();
}

}  // namespace luxel
