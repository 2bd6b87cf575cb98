// File-system helpers for the stores. Every store write goes through
// write_file_atomic (common/atomic_file.h: temporary file, fsync, rename over
// the target, fsync of the directory), so a crash leaves the old or the new
// version.
#pragma once

#include <string>

#include "common/atomic_file.h"
#include "common/status.h"

namespace luxel::service {

// rename(2) then fsync of the destination's directory.
Status rename_durable(const std::string& from, const std::string& to);
// Creates `dir` and its parents; INTERNAL naming the path on failure.
Status make_directories(const std::string& dir);
// Removes a file or a folder tree; errors are logged, never fatal.
void remove_tree(const std::string& path);

// 32 lowercase hex digits from the system's random source (bake ids).
std::string random_hex_id();
// Seconds since the Unix epoch.
double unix_now();

}  // namespace luxel::service
