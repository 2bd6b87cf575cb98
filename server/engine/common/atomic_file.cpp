#include "common/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace luxel {
namespace {

// Maps an errno from creating/writing/renaming `path` onto a Status: problems
// the caller can fix (a bad or read-only destination) are INVALID_ARGUMENT.
Status errno_status(int err, const char* action, const std::string& path) {
  std::string msg = strprintf("%s '%s': %s", action, path.c_str(), std::strerror(err));
  switch (err) {
    case ENOENT:
    case ENOTDIR:
    case EACCES:
    case EPERM:
    case EROFS:
    case EISDIR:
    case ENAMETOOLONG:
    case ELOOP:
      return invalid_argument(std::move(msg) + " (is the directory present and writable?)");
    case ENOSPC:
    case EDQUOT:
      return resource_exhausted(std::move(msg));
    default:
      return internal_error(std::move(msg));
  }
}

Status write_all(int fd, const void* data, size_t bytes, const std::string& tmp) {
  const auto* p = static_cast<const unsigned char*>(data);
  while (bytes > 0) {
    const ssize_t n = ::write(fd, p, bytes);
    if (n < 0) {
      if (errno == EINTR) continue;
      return errno_status(errno, "cannot write", tmp);
    }
    p += n;
    bytes -= static_cast<size_t>(n);
  }
  return Status::ok();
}

Status sync_directory_of(const std::string& path) {
  std::filesystem::path dir = std::filesystem::path(path).parent_path();
  if (dir.empty()) dir = ".";
  return fsync_directory(dir.string());
}

}  // namespace

// fsync of the directory entry makes a rename durable. File systems that
// cannot sync directories answer EINVAL; nothing more can be done there.
Status fsync_directory(const std::string& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return errno_status(errno, "cannot open directory", dir);
  const int rc = ::fsync(fd);
  const int err = errno;
  ::close(fd);
  if (rc != 0 && err != EINVAL && err != EROFS)
    return errno_status(err, "cannot fsync directory", dir);
  return Status::ok();
}

std::string atomic_temp_path(const std::string& path) {
  return path + ".tmp";
}

Status write_file_atomic(const std::string& path, const void* data, size_t bytes) {
  if (bytes > 0 && data == nullptr)
    return invalid_argument(strprintf("write_file_atomic '%s': no data", path.c_str()));
  return write_file_atomic_with(
      path, [&](int fd, const std::string& tmp) { return write_all(fd, data, bytes, tmp); });
}

Status write_file_atomic_with(const std::string& path,
                              const std::function<Status(int fd, const std::string& tmp)>& fill) {
  if (path.empty()) return invalid_argument("write_file_atomic: empty output path");
  const std::string tmp = atomic_temp_path(path);
  const int fd = ::open(tmp.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return errno_status(errno, "cannot create", tmp);
  Status st = fill(fd, tmp);
  if (st.is_ok() && ::fsync(fd) != 0) st = errno_status(errno, "cannot fsync", tmp);
  // close() reports deferred write errors on some file systems (NFS).
  if (::close(fd) != 0 && st.is_ok()) st = errno_status(errno, "cannot close", tmp);
  if (st.is_ok() && ::rename(tmp.c_str(), path.c_str()) != 0)
    st = errno_status(errno, "cannot rename temporary file onto", path);
  if (!st.is_ok()) {
    ::unlink(tmp.c_str());
    return st;
  }
  return sync_directory_of(path);
}

Result<std::string> read_whole_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return not_found(strprintf("%s: cannot open", path.c_str()));
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) return internal_error(strprintf("%s: read failed", path.c_str()));
  return ss.str();
}

}  // namespace luxel
