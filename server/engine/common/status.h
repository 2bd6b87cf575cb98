// Status and Result<T>: how the engine reports user-facing errors.
//
// Two tiers of errors (STYLE.md, practice 8): invariants use LUXEL_CHECK and
// abort; everything a user can cause (a bad file, a bad setting, a missing
// device) returns a Status whose message names the thing at fault. The service
// maps StatusCode one-to-one onto gRPC status codes.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <utility>

namespace luxel {

enum class StatusCode {
  kOk = 0,
  kInvalidArgument,    // bad input: file content, settings
  kNotFound,           // missing file, buffer, image, device
  kDataLoss,           // truncated or corrupt data
  kResourceExhausted,  // a limit was hit (memory, size)
  kUnavailable,        // no OpenCL device / driver failure
  kDeadlineExceeded,   // a time limit was hit (an import's --import-timeout)
  kInternal,           // a bug or an unexpected driver error
  kUnauthenticated,    // credentials refused (a coordinator's token at a worker)
};

const char* status_code_name(StatusCode code);

class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(StatusCode code, std::string message) : code_(code), message_(std::move(message)) {}

  static Status ok() { return {}; }
  bool is_ok() const { return code_ == StatusCode::kOk; }
  explicit operator bool() const { return is_ok(); }
  StatusCode code() const { return code_; }
  const std::string& message() const { return message_; }
  // "INVALID_ARGUMENT: mesh 'floor' accessor 3: ..."
  std::string to_string() const;

 private:
  StatusCode code_ = StatusCode::kOk;
  std::string message_;
};

// printf-style formatting into a std::string (libstdc++ 12 has no std::format).
std::string strprintf(const char* fmt, ...) __attribute__((format(printf, 1, 2)));

inline Status invalid_argument(std::string m) {
  return {StatusCode::kInvalidArgument, std::move(m)};
}
inline Status not_found(std::string m) {
  return {StatusCode::kNotFound, std::move(m)};
}
inline Status data_loss(std::string m) {
  return {StatusCode::kDataLoss, std::move(m)};
}
inline Status resource_exhausted(std::string m) {
  return {StatusCode::kResourceExhausted, std::move(m)};
}
inline Status deadline_exceeded(std::string m) {
  return {StatusCode::kDeadlineExceeded, std::move(m)};
}
inline Status unavailable(std::string m) {
  return {StatusCode::kUnavailable, std::move(m)};
}
inline Status internal_error(std::string m) {
  return {StatusCode::kInternal, std::move(m)};
}

// A value or an error Status.
template <typename T>
class [[nodiscard]] Result {
 public:
  Result(T value) : value_(std::move(value)) {}         // NOLINT: implicit by design
  Result(Status status) : status_(std::move(status)) {  // NOLINT
    if (status_.is_ok()) status_ = internal_error("Result constructed from an OK status");
  }
  bool is_ok() const { return value_.has_value(); }
  explicit operator bool() const { return is_ok(); }
  const Status& status() const { return status_; }
  T& value() & { return *value_; }
  const T& value() const& { return *value_; }
  T&& value() && { return std::move(*value_); }
  T* operator->() { return &*value_; }
  const T* operator->() const { return &*value_; }
  T& operator*() { return *value_; }

 private:
  std::optional<T> value_;
  Status status_;
};

[[noreturn]] void check_failed(const char* expr, const char* file, int line, const char* msg);

}  // namespace luxel

// Invariant checks: always on (cheap), abort with location. Not for user errors.
#define LUXEL_CHECK(expr)                                                   \
  do {                                                                      \
    if (!(expr)) ::luxel::check_failed(#expr, __FILE__, __LINE__, nullptr); \
  } while (0)
#define LUXEL_CHECK_MSG(expr, msg)                                        \
  do {                                                                    \
    if (!(expr)) ::luxel::check_failed(#expr, __FILE__, __LINE__, (msg)); \
  } while (0)

// Propagate an error Status from an expression returning Status.
#define LUXEL_RETURN_IF_ERROR(expr)           \
  do {                                        \
    ::luxel::Status _luxel_st = (expr);       \
    if (!_luxel_st.is_ok()) return _luxel_st; \
  } while (0)
