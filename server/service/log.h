// Structured logs: one line per event on stderr, so a log shipper or grep can
// follow a bake, a scene or a request by its id. Two formats (--log-format):
//   text (default): key=value pairs
//     ts=2024-05-01T12:00:00.123Z event=bake_started bake=9f.. scene=3a..
//     Values with spaces, quotes or '=' are quoted with "..." (quotes escaped,
//     control bytes as \xHH).
//   json: one object per line
//     {"ts":"2024-05-01T12:00:00.123Z","level":"info","event":"bake_started",
//      "bake_id":"9f..","scene_id":"3a..","request_id":"..."}
//     The field keys "bake" and "scene" become "bake_id" and "scene_id".
//     Any byte string gives valid JSON: control characters as \u00XX,
//     invalid UTF-8 as U+FFFD.
// Lines written while a thread serves an RPC carry that RPC's request id
// (set_thread_request_id, called where the handler starts).
#pragma once

#include <chrono>
#include <cstdint>
#include <initializer_list>
#include <mutex>
#include <string>
#include <utility>

namespace luxel::service {

using LogField = std::pair<const char*, std::string>;

enum class LogFormat { kText, kJson };
enum class LogLevel { kInfo, kWarn, kError };

// Process-wide; set once at startup, before other threads log.
void set_log_format(LogFormat format);
LogFormat log_format();

// The request id this thread's lines carry ("" = none).
void set_thread_request_id(std::string id);

// Writes one line atomically with respect to other log_event calls. The
// level follows from the event name (fatal, warning, *_failed, *_refused,
// unauthenticated, ... are warnings or errors; the rest info).
void log_event(const char* event, std::initializer_list<LogField> fields = {});
void log_event(LogLevel level, const char* event, std::initializer_list<LogField> fields = {});

// At most one line per `period` for an event a client can trigger at will
// (a flood of unauthenticated calls must not flood the log). Thread-safe.
class LogThrottle {
 public:
  using Clock = std::chrono::steady_clock;
  explicit LogThrottle(Clock::duration period) : period_(period) {}
  // True when the line at `now` is to be written; `suppressed` then receives
  // how many were held back since the last line written.
  bool admit(Clock::time_point now, uint64_t* suppressed);

 private:
  std::mutex mu_;
  const Clock::duration period_;
  bool any_ = false;
  Clock::time_point last_{};
  uint64_t held_ = 0;
};

// JSON string literal (with the quotes) of any byte string: valid UTF-8 is
// kept, control characters become \u00XX, invalid sequences U+FFFD.
std::string json_quote(const std::string& bytes);

}  // namespace luxel::service
