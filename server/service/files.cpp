#include "service/files.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "common/atomic_file.h"
#include "service/log.h"

namespace luxel::service {

namespace fs = std::filesystem;

Status rename_durable(const std::string& from, const std::string& to) {
  if (::rename(from.c_str(), to.c_str()) != 0)
    return internal_error(
        strprintf("rename %s -> %s: %s", from.c_str(), to.c_str(), std::strerror(errno)));
  return fsync_directory(fs::path(to).parent_path().string());
}

Status make_directories(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec)
    return internal_error(strprintf("%s: cannot create: %s", dir.c_str(), ec.message().c_str()));
  return Status::ok();
}

void remove_tree(const std::string& path) {
  std::error_code ec;
  fs::remove_all(path, ec);
  if (ec) log_event("remove_failed", {{"path", path}, {"error", ec.message()}});
}

std::string random_hex_id() {
  std::random_device rd;
  std::string id;
  static const char* kHex = "0123456789abcdef";
  for (int i = 0; i < 4; ++i) {
    const uint32_t v = rd();
    for (int k = 0; k < 8; ++k) id += kHex[(v >> (4 * k)) & 15];
  }
  return id;
}

double unix_now() {
  using namespace std::chrono;
  return duration<double>(system_clock::now().time_since_epoch()).count();
}

}  // namespace luxel::service
