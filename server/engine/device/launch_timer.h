// Per-name kernel timings from OpenCL profiling events (like Table 5.4 of the
// core thesis: time per pipeline stage).
#pragma once

#include <CL/cl.h>

#include <map>
#include <string>
#include <vector>

#include "common/status.h"

namespace luxel::device {

struct LaunchStats {
  uint64_t launches = 0;
  double total_ms = 0.0;  // device execution time (CL_PROFILING_COMMAND_START..END)
  double max_ms = 0.0;
};

class LaunchTimer {
 public:
  LaunchTimer() = default;
  LaunchTimer(const LaunchTimer&) = delete;
  LaunchTimer& operator=(const LaunchTimer&) = delete;
  ~LaunchTimer();

  // Takes ownership of the event (released after collect()).
  void record(const std::string& name, cl_event event);
  // A stage that ran on the host (the Embree intersector), timed there.
  void record_host(const std::string& name, double ms);
  // Reads the profiling info of every recorded event; call after clFinish.
  Status collect();
  void reset();

  const std::map<std::string, LaunchStats>& stats() const { return stats_; }
  double total_ms() const;
  // Table sorted by total time: name, launches, total ms, mean ms, max ms, share.
  std::string table() const;

 private:
  std::vector<std::pair<std::string, cl_event>> pending_;
  std::map<std::string, LaunchStats> stats_;
};

}  // namespace luxel::device
