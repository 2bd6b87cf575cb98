#include "common/uri.h"

namespace luxel {
namespace {

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

}  // namespace

Result<std::string> percent_decode_uri(std::string_view uri) {
  std::string out;
  out.reserve(uri.size());
  for (size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] != '%') {
      out.push_back(uri[i]);
      continue;
    }
    const int hi = i + 1 < uri.size() ? hex_value(uri[i + 1]) : -1;
    const int lo = i + 2 < uri.size() ? hex_value(uri[i + 2]) : -1;
    if (hi < 0 || lo < 0) {
      const std::string escape(uri.substr(i, 3));
      return invalid_argument(
          strprintf("uri '%.*s': malformed percent-escape '%s' at byte %zu (expected '%%' and two "
                    "hex digits)",
                    static_cast<int>(uri.size()), uri.data(), escape.c_str(), i));
    }
    if (hi == 0 && lo == 0)
      return invalid_argument(
          strprintf("uri '%.*s': '%%00' at byte %zu would put a NUL byte in a file name",
                    static_cast<int>(uri.size()), uri.data(), i));
    out.push_back(static_cast<char>(hi * 16 + lo));
    i += 2;
  }
  return out;
}

}  // namespace luxel
