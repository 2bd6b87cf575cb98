// A cancel request as the long steps of a bake see it: the host's flag
// (BakeHooks::cancel, set by CancelBake or a shutdown), polled between the
// steps of setup and inside their loops (UV charting and packing, the
// BVH build's progress monitor, sample-info and tile planning, buffer
// clears), so that a bake stops within a fraction of a second in every
// phase, not only between iterations.
//
// A step that stops returns cancelled_error(): UNAVAILABLE with a message
// naming the step. The host that set the flag knows it asked, and reads a
// failed job with its flag set as cancelled (service/bake_runner.cpp).
#pragma once

#include <atomic>

#include "common/status.h"

namespace luxel {

class CancelToken {
 public:
  CancelToken() = default;
  explicit CancelToken(const std::atomic<bool>* flag) : flag_(flag) {}
  bool requested() const { return flag_ && flag_->load(std::memory_order_relaxed); }
  const std::atomic<bool>* flag() const { return flag_; }

 private:
  const std::atomic<bool>* flag_ = nullptr;
};

inline Status cancelled_error(const char* step) {
  return unavailable(std::string("cancelled during ") + step);
}

// OK, or cancelled_error(step) when the request is set.
inline Status check_cancel(const CancelToken& cancel, const char* step) {
  return cancel.requested() ? cancelled_error(step) : Status::ok();
}

}  // namespace luxel
