// Kernel sources: embedded at build time from kernels/ (see
// cmake/EmbedKernels.cmake), or read from a development folder named by the
// LUXEL_KERNEL_DIR environment variable. Never relative to the working
// directory.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "common/status.h"

namespace luxel::device {

struct EmbeddedKernelFile {
  const char* path;  // relative to kernels/, e.g. "shared/geometry.h"
  std::string_view text;
};

// The table generated at build time.
const std::vector<EmbeddedKernelFile>& embedded_kernel_files();

// One kernel file by relative path: LUXEL_KERNEL_DIR/<path> when that
// variable is set, else the embedded copy.
Result<std::string> read_kernel_file(const std::string& path);

// `entry` with every `#include "..."` (relative to kernels/) expanded
// recursively, each file at most once, with #line markers so compiler
// messages point at the original files. The result is self-contained: it is
// what gets hashed for the program cache and kept when a build fails.
Result<std::string> expand_kernel_source(const std::string& entry);

}  // namespace luxel::device
