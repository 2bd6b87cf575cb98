#include "service/data_dir_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

namespace luxel::service {

Result<DataDirLock> DataDirLock::acquire(const std::string& data_dir) {
  std::error_code ec;
  const bool created = std::filesystem::create_directories(data_dir, ec);
  if (ec)
    return unavailable(
        strprintf("--data-dir %s: cannot create it: %s", data_dir.c_str(), ec.message().c_str()));
  // Uploaded scenes and results are the clients' data: private to the
  // daemon's user whatever umask it was started with. A directory that
  // already existed keeps the mode its owner gave it.
  if (created && ::chmod(data_dir.c_str(), 0700) != 0)
    return unavailable(strprintf("--data-dir %s: cannot chmod it to 0700: %s", data_dir.c_str(),
                                 std::strerror(errno)));
  const std::string path = data_dir + "/luxeld.lock";
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0600);
  if (fd < 0)
    return unavailable(strprintf("--data-dir %s: cannot open %s: %s", data_dir.c_str(),
                                 path.c_str(), std::strerror(errno)));
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    char pid[32] = {0};
    const ssize_t n = ::pread(fd, pid, sizeof(pid) - 1, 0);
    ::close(fd);
    std::string holder = n > 0 ? std::string(pid, static_cast<size_t>(n)) : "unknown";
    while (!holder.empty() && (holder.back() == '\n' || holder.back() == ' ')) holder.pop_back();
    if (err == EWOULDBLOCK)
      return unavailable(strprintf(
          "--data-dir %s is in use by another luxeld (pid %s, lock %s); one daemon per data "
          "dir",
          data_dir.c_str(), holder.c_str(), path.c_str()));
    return unavailable(strprintf("--data-dir %s: cannot lock %s: %s", data_dir.c_str(),
                                 path.c_str(), std::strerror(err)));
  }
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (::ftruncate(fd, 0) != 0 ||
      ::pwrite(fd, pid.data(), pid.size(), 0) != static_cast<ssize_t>(pid.size())) {
    const int err = errno;
    ::close(fd);
    return unavailable(strprintf("--data-dir %s: cannot write %s: %s", data_dir.c_str(),
                                 path.c_str(), std::strerror(err)));
  }
  return DataDirLock(fd);
}

DataDirLock::~DataDirLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the lock
}

}  // namespace luxel::service
