// Printing shared by the generators of committed tables
// (make_ggx_albedo_table.cpp, make_ad_specular_lut.cpp): the "GENERATED, do
// not edit" banner, rows of C float literals, and writing the header to --out
// or standard output. Header-only: the tests include the generators' .cpp
// files, which include this.
#pragma once

#include <algorithm>
#include <cstdarg>
#include <cstddef>
#include <cstdio>
#include <initializer_list>
#include <string>

namespace luxel_tables {

// Appends printf output (at most 511 characters) to out.
__attribute__((format(printf, 2, 3))) inline void appendf(std::string& out, const char* format,
                                                          ...) {
  char buf[512];
  va_list args;
  va_start(args, format);
  std::vsnprintf(buf, sizeof buf, format, args);
  va_end(args);
  out += buf;
}

// Opens the generated header's comment: "/* " before the first of `lines`,
// " * " before each further one, then the command that regenerates the file
// (indented) and an empty comment line. The lines are the caller's, wrapped as
// its committed header has them.
inline void append_banner(std::string& out, std::initializer_list<const char*> lines,
                          const std::string& command) {
  const char* lead = "/* ";
  for (const char* line : lines) {
    out += lead;
    out += line;
    out += "\n";
    lead = " * ";
  }
  out += " *   " + command + "\n *\n";
}

// Appends `count` floats as C literals " <value>f,", `per_line` to a line,
// each line indented by three spaces. A value prints as printf's %g with
// `digits` significant digits; `alternate` (%#g) keeps the decimal point and
// trailing zeros.
inline void append_float_rows(std::string& out, const float* values, size_t count, size_t per_line,
                              int digits, bool alternate) {
  for (size_t i = 0; i < count; i += per_line) {
    out += "   ";
    for (size_t k = i; k < std::min(i + per_line, count); ++k) {
      if (alternate)
        appendf(out, " %#.*gf,", digits, double(values[k]));
      else
        appendf(out, " %.*gf,", digits, double(values[k]));
    }
    out += "\n";
  }
}

// Writes the generated header to out_path (--out), or to standard output when
// out_path is null. False, with a message on stderr, when the file cannot be
// written.
inline bool write_table(const std::string& text, const char* out_path) {
  if (!out_path) {
    std::fputs(text.c_str(), stdout);
    return true;
  }
  FILE* f = std::fopen(out_path, "wb");
  if (!f || std::fwrite(text.data(), 1, text.size(), f) != text.size() || std::fclose(f) != 0) {
    std::fprintf(stderr, "cannot write %s\n", out_path);
    return false;
  }
  return true;
}

}  // namespace luxel_tables
