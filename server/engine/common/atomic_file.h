// Crash-safe file replacement.
//
// Every file the engine, the daemon and the CLI write is written whole or not at all: bytes
// go to "<path>.tmp", which is fsync'ed and renamed over `path` (rename is
// atomic on POSIX file systems), then the directory is fsync'ed so the rename
// itself survives a power cut. A crash therefore leaves either the old file or
// the new one, never a torn one; at worst a stale "<path>.tmp" remains, which
// the next write to `path` truncates and reuses.
//
// Two writers of the same `path` at the same time share "<path>.tmp" and may
// clobber each other's temporary; callers serialise writes per path (each bake
// writes into its own result folder).
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <string_view>

#include "common/status.h"

namespace luxel {

// Replaces `path` atomically with `bytes` bytes from `data` (permissions 0644
// before the umask). Errors name the path:
//   INVALID_ARGUMENT   empty path, missing or unwritable directory, path is a directory
//   RESOURCE_EXHAUSTED the disk or quota is full
//   INTERNAL           any other I/O failure
// On error no "<path>.tmp" is left behind and `path` is unchanged.
Status write_file_atomic(const std::string& path, const void* data, size_t bytes);
inline Status write_file_atomic(const std::string& path, std::string_view bytes) {
  return write_file_atomic(path, bytes.data(), bytes.size());
}

// The same with the bytes written by `fill` into the open temporary `fd`
// (it may seek; the file is fsync'ed, closed and renamed after it returns
// OK): an encoder streams a large file to disk instead of holding all of it
// in memory first. `tmp` names the temporary in fill's errors.
Status write_file_atomic_with(const std::string& path,
                              const std::function<Status(int fd, const std::string& tmp)>& fill);

// Makes renames and creations inside `dir` durable (fsync of the directory).
Status fsync_directory(const std::string& dir);

// The whole file at `path`, its reading counterpart: NOT_FOUND when it
// cannot be opened, INTERNAL when the read fails; both name the path.
Result<std::string> read_whole_file(const std::string& path);

// The temporary name write_file_atomic uses for `path` ("<path>.tmp").
std::string atomic_temp_path(const std::string& path);

}  // namespace luxel
