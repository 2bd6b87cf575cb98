#include "service/log.h"

#include <sys/time.h>

#include <cstdio>
#include <ctime>
#include <mutex>

#include "common/status.h"

namespace luxel::service {
namespace {

// A value longer than this is cut (with its length said), so one request
// cannot write megabytes into the log.
constexpr size_t kMaxLoggedValue = 1024;

// One line per event whatever a value holds: control bytes (NUL, CR, LF,
// ESC, ...) are escaped as \xHH inside quotes, quotes and backslashes too.
std::string quote_if_needed(const std::string& in) {
  std::string v = in.size() > kMaxLoggedValue
                      ? in.substr(0, kMaxLoggedValue) + strprintf("...(%zu bytes)", in.size())
                      : in;
  bool plain = !v.empty();
  for (char c : v) {
    const auto u = static_cast<unsigned char>(c);
    if (c == ' ' || c == '"' || c == '=' || c == '\\' || u < 0x20 || u == 0x7f) plain = false;
  }
  if (plain) return v;
  std::string q = "\"";
  for (char c : v) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7f) {
      q += strprintf("\\x%02x", u);
      continue;
    }
    if (c == '"' || c == '\\') q += '\\';
    q += c;
  }
  return q + "\"";
}

std::string utc_timestamp() {
  timeval tv{};
  gettimeofday(&tv, nullptr);
  std::tm tm{};
  gmtime_r(&tv.tv_sec, &tm);
  char buf[64];
  std::snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900,
                tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec,
                static_cast<int>(tv.tv_usec / 1000));
  return buf;
}

}  // namespace

void log_event(const char* event, std::initializer_list<LogField> fields) {
  std::string line = "ts=" + utc_timestamp() + " event=" + event;
  for (const auto& [key, value] : fields)
    line += std::string(" ") + key + "=" + quote_if_needed(value);
  line += '\n';
  static std::mutex mu;
  std::lock_guard<std::mutex> lock(mu);
  std::fputs(line.c_str(), stderr);
  std::fflush(stderr);
}

}  // namespace luxel::service
