#include "device/kernel_sources.h"

#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>

namespace luxel::device {
namespace {

Status expand_into(const std::string& path, std::set<std::string>& seen, int depth,
                   std::string& out) {
  if (depth > 32) return invalid_argument("kernel include depth exceeds 32 at '" + path + "'");
  if (!seen.insert(path).second) return Status::ok();
  auto text = read_kernel_file(path);
  if (!text) return text.status();
  std::istringstream in(text.value());
  std::string line;
  int line_no = 0;
  out += strprintf("#line 1 \"%s\"\n", path.c_str());
  while (std::getline(in, line)) {
    ++line_no;
    const size_t first = line.find_first_not_of(" \t");
    if (first != std::string::npos && line.compare(first, 8, "#include") == 0) {
      const size_t open = line.find('"', first + 8);
      const size_t close = open == std::string::npos ? open : line.find('"', open + 1);
      if (open != std::string::npos && close != std::string::npos) {
        const std::string inc = line.substr(open + 1, close - open - 1);
        LUXEL_RETURN_IF_ERROR(expand_into(inc, seen, depth + 1, out));
        out += strprintf("#line %d \"%s\"\n", line_no + 1, path.c_str());
        continue;
      }
    }
    out += line;
    out += '\n';
  }
  return Status::ok();
}

}  // namespace

Result<std::string> read_kernel_file(const std::string& path) {
  if (path.find("..") != std::string::npos || (!path.empty() && path[0] == '/'))
    return invalid_argument("kernel path '" + path + "' must be relative to kernels/");
  if (const char* dir = std::getenv("LUXEL_KERNEL_DIR"); dir && *dir) {
    const std::string full = std::string(dir) + "/" + path;
    std::ifstream f(full, std::ios::binary);
    if (!f) return not_found("kernel file '" + full + "' (LUXEL_KERNEL_DIR) not found");
    std::ostringstream ss;
    ss << f.rdbuf();
    return ss.str();
  }
  for (const auto& file : embedded_kernel_files())
    if (path == file.path) return std::string(file.text);
  return not_found("kernel file '" + path + "' is not among the embedded kernels");
}

Result<std::string> expand_kernel_source(const std::string& entry) {
  std::set<std::string> seen;
  std::string out;
  LUXEL_RETURN_IF_ERROR(expand_into(entry, seen, 0, out));
  return out;
}

}  // namespace luxel::device
