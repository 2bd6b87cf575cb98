#include "device/launch_timer.h"

#include <algorithm>

#include "device/cl_error.h"

namespace luxel::device {

LaunchTimer::~LaunchTimer() {
  reset();
}

void LaunchTimer::record(const std::string& name, cl_event event) {
  pending_.emplace_back(name, event);
}

void LaunchTimer::record_host(const std::string& name, double ms) {
  LaunchStats& s = stats_[name];
  s.launches += 1;
  s.total_ms += ms;
  s.max_ms = std::max(s.max_ms, ms);
}

Status LaunchTimer::collect() {
  Status result;
  for (auto& [name, event] : pending_) {
    cl_ulong start = 0, end = 0;
    cl_int err =
        clGetEventProfilingInfo(event, CL_PROFILING_COMMAND_START, sizeof start, &start, nullptr);
    if (err == CL_SUCCESS)
      err = clGetEventProfilingInfo(event, CL_PROFILING_COMMAND_END, sizeof end, &end, nullptr);
    clReleaseEvent(event);
    if (err != CL_SUCCESS) {
      if (result.is_ok()) result = cl_status(err, "profiling info of launch '" + name + "'");
      continue;
    }
    LaunchStats& s = stats_[name];
    const double ms = end > start ? static_cast<double>(end - start) * 1e-6 : 0.0;
    s.launches += 1;
    s.total_ms += ms;
    s.max_ms = std::max(s.max_ms, ms);
  }
  pending_.clear();
  return result;
}

void LaunchTimer::reset() {
  for (auto& p : pending_) clReleaseEvent(p.second);
  pending_.clear();
  stats_.clear();
}

double LaunchTimer::total_ms() const {
  double t = 0;
  for (const auto& [name, s] : stats_) t += s.total_ms;
  return t;
}

std::string LaunchTimer::table() const {
  std::vector<std::pair<std::string, LaunchStats>> rows(stats_.begin(), stats_.end());
  std::sort(rows.begin(), rows.end(),
            [](const auto& a, const auto& b) { return a.second.total_ms > b.second.total_ms; });
  const double total = total_ms();
  std::string out = strprintf("%-28s %9s %12s %10s %10s %7s\n", "kernel", "launches", "total ms",
                              "mean ms", "max ms", "share");
  for (const auto& [name, s] : rows) {
    out += strprintf("%-28s %9llu %12.3f %10.3f %10.3f %6.1f%%\n", name.c_str(),
                     static_cast<unsigned long long>(s.launches), s.total_ms,
                     s.launches ? s.total_ms / static_cast<double>(s.launches) : 0.0, s.max_ms,
                     total > 0 ? 100.0 * s.total_ms / total : 0.0);
  }
  out += strprintf("%-28s %9s %12.3f\n", "total", "", total);
  return out;
}

}  // namespace luxel::device
