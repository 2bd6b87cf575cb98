// One luxeld per --data-dir: an exclusive flock(2) on <data-dir>/luxeld.lock,
// held for the daemon's life (the kernel drops it when the process dies, so
// a kill -9 never leaves a stale lock). A second daemon on the same folder
// would delete the first's in-flight uploads and re-run its RUNNING bakes.
#pragma once

#include <string>

#include "common/status.h"

namespace luxel::service {

class DataDirLock {
 public:
  // Creates the folder if needed, takes the lock and writes this process's
  // pid into the lock file. UNAVAILABLE naming the holder's pid when
  // another process holds it.
  static Result<DataDirLock> acquire(const std::string& data_dir);

  DataDirLock(DataDirLock&& other) noexcept : fd_(other.fd_) { other.fd_ = -1; }
  DataDirLock& operator=(DataDirLock&&) = delete;
  DataDirLock(const DataDirLock&) = delete;
  ~DataDirLock();

 private:
  explicit DataDirLock(int fd) : fd_(fd) {}
  int fd_ = -1;
};

}  // namespace luxel::service
