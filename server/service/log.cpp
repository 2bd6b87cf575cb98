#include "service/log.h"

#include <sys/time.h>

#include <atomic>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <mutex>

#include "common/status.h"

namespace luxel::service {
namespace {

// A value longer than this is cut (with its length said), so one request
// cannot write megabytes into the log.
constexpr size_t kMaxLoggedValue = 1024;

std::atomic<LogFormat> g_format{LogFormat::kText};
thread_local std::string t_request_id;

std::string cut(const std::string& in) {
  return in.size() > kMaxLoggedValue
             ? in.substr(0, kMaxLoggedValue) + strprintf("...(%zu bytes)", in.size())
             : in;
}

// One line per event whatever a value holds: control bytes (NUL, CR, LF,
// ESC, ...) are escaped as \xHH inside quotes, quotes and backslashes too.
std::string quote_if_needed(const std::string& in) {
  std::string v = cut(in);
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

// Length of the well-formed UTF-8 sequence at s[i] (RFC 3629: no overlong
// forms, no surrogates, nothing past U+10FFFF), 0 when it is not one.
size_t utf8_sequence_length(const std::string& s, size_t i) {
  const auto b = [&](size_t k) { return static_cast<unsigned char>(s[k]); };
  const unsigned char c = b(i);
  size_t n = 0;
  unsigned char lo = 0x80, hi = 0xbf;  // allowed range of the second byte
  if (c >= 0xc2 && c <= 0xdf)
    n = 2;
  else if (c >= 0xe0 && c <= 0xef) {
    n = 3;
    if (c == 0xe0) lo = 0xa0;  // overlong
    if (c == 0xed) hi = 0x9f;  // surrogates
  } else if (c >= 0xf0 && c <= 0xf4) {
    n = 4;
    if (c == 0xf0) lo = 0x90;  // overlong
    if (c == 0xf4) hi = 0x8f;  // past U+10FFFF
  } else
    return 0;
  if (i + n > s.size()) return 0;
  if (b(i + 1) < lo || b(i + 1) > hi) return 0;
  for (size_t k = 2; k < n; ++k)
    if (b(i + k) < 0x80 || b(i + k) > 0xbf) return 0;
  return n;
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

bool ends_with(const char* s, const char* suffix) {
  const size_t n = std::strlen(s), m = std::strlen(suffix);
  return n >= m && std::strcmp(s + n - m, suffix) == 0;
}

LogLevel level_of(const char* event) {
  if (std::strcmp(event, "fatal") == 0) return LogLevel::kError;
  if (std::strcmp(event, "warning") == 0 || std::strcmp(event, "unauthenticated") == 0 ||
      std::strcmp(event, "device_unavailable") == 0 || ends_with(event, "_failed") ||
      ends_with(event, "_refused"))
    return LogLevel::kWarn;
  return LogLevel::kInfo;
}

const char* level_name(LogLevel level) {
  switch (level) {
    case LogLevel::kWarn:
      return "warn";
    case LogLevel::kError:
      return "error";
    case LogLevel::kInfo:
      break;
  }
  return "info";
}

// JSON keys say what the id is; text keeps its short, established keys.
const char* json_key(const char* key) {
  if (std::strcmp(key, "bake") == 0) return "bake_id";
  if (std::strcmp(key, "scene") == 0) return "scene_id";
  return key;
}

std::string text_line(const char* event, std::initializer_list<LogField> fields) {
  std::string line = "ts=" + utc_timestamp() + " event=" + event;
  bool has_request_id = false;
  for (const auto& [key, value] : fields) {
    line += std::string(" ") + key + "=" + quote_if_needed(value);
    has_request_id |= std::strcmp(key, "request_id") == 0;
  }
  if (!t_request_id.empty() && !has_request_id)
    line += " request_id=" + quote_if_needed(t_request_id);
  return line;
}

std::string json_line(LogLevel level, const char* event, std::initializer_list<LogField> fields) {
  std::string line = "{\"ts\":\"" + utc_timestamp() + "\",\"level\":\"" + level_name(level) +
                     "\",\"event\":" + json_quote(event);
  bool has_request_id = false;
  for (const auto& [key, value] : fields) {
    line += "," + json_quote(json_key(key)) + ":" + json_quote(cut(value));
    has_request_id |= std::strcmp(key, "request_id") == 0;
  }
  if (!t_request_id.empty() && !has_request_id)
    line += ",\"request_id\":" + json_quote(t_request_id);
  return line + "}";
}

}  // namespace

void set_log_format(LogFormat format) {
  g_format = format;
}

LogFormat log_format() {
  return g_format.load();
}

void set_thread_request_id(std::string id) {
  t_request_id = std::move(id);
}

std::string json_quote(const std::string& s) {
  std::string q = "\"";
  for (size_t i = 0; i < s.size();) {
    const auto u = static_cast<unsigned char>(s[i]);
    if (u < 0x80) {
      if (u == '"' || u == '\\') {
        q += '\\';
        q += static_cast<char>(u);
      } else if (u < 0x20 || u == 0x7f) {
        q += strprintf("\\u%04x", u);
      } else {
        q += static_cast<char>(u);
      }
      ++i;
      continue;
    }
    const size_t n = utf8_sequence_length(s, i);
    if (n == 0) {
      q += "\\ufffd";  // one replacement per invalid byte
      ++i;
    } else {
      q.append(s, i, n);
      i += n;
    }
  }
  return q + "\"";
}

void log_event(const char* event, std::initializer_list<LogField> fields) {
  log_event(level_of(event), event, fields);
}

void log_event(LogLevel level, const char* event, std::initializer_list<LogField> fields) {
  std::string line =
      log_format() == LogFormat::kJson ? json_line(level, event, fields) : text_line(event, fields);
  line += '\n';
  static std::mutex mu;
  std::lock_guard<std::mutex> lock(mu);
  std::fputs(line.c_str(), stderr);
  std::fflush(stderr);
}

bool LogThrottle::admit(Clock::time_point now, uint64_t* suppressed) {
  std::lock_guard<std::mutex> lock(mu_);
  if (any_ && now - last_ < period_) {
    ++held_;
    return false;
  }
  any_ = true;
  last_ = now;
  *suppressed = held_;
  held_ = 0;
  return true;
}

}  // namespace luxel::service
