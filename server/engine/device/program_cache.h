// Builds OpenCL programs and caches their binaries on disk.
//
// Cache key: hash of the expanded source, the build options (FeatureSet), the
// device name and version, the driver version, the platform and Luxel's
// version. A hit skips the OpenCL compiler entirely (PoCL takes seconds per
// program). A failed build keeps the build log and the expanded source under
// <cache>/failed/ and returns them in the error.
//
// Cache folder: $LUXEL_CACHE_DIR, else $XDG_CACHE_HOME/luxel/programs, else
// ~/.cache/luxel/programs. Writes are atomic (temp file + rename), so
// concurrent processes sharing a cache never read a torn binary.
#pragma once

#include <CL/cl.h>

#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "common/status.h"
#include "device/context.h"
#include "device/feature_set.h"

namespace luxel::device {

class Program {
 public:
  Program(cl_program p, std::string key, bool from_disk, double build_ms)
      : program_(p), key_(std::move(key)), from_disk_(from_disk), build_ms_(build_ms) {}
  ~Program();
  Program(const Program&) = delete;
  Program& operator=(const Program&) = delete;

  Result<Kernel> kernel(const std::string& name) const;
  const std::string& key() const { return key_; }
  bool from_disk_cache() const { return from_disk_; }
  double build_ms() const { return build_ms_; }

 private:
  cl_program program_;
  std::string key_;
  bool from_disk_;
  double build_ms_;
};

class ProgramCache {
 public:
  ProgramCache(cl_context context, DeviceInfo device);

  // The program built from kernels/<entry> with `features` (in memory after the
  // first call; from disk when a previous process built it).
  Result<const Program*> get(const std::string& entry, const FeatureSet& features);

  static std::string cache_dir();

 private:
  Result<cl_program> build_from_source(const std::string& source, const std::string& options,
                                       const std::string& key, const std::string& entry);
  cl_program load_binary(const std::string& path, const std::string& options);
  void store_binary(cl_program program, const std::string& path);

  cl_context context_;
  DeviceInfo device_;
  std::mutex mutex_;
  std::map<std::string, std::unique_ptr<Program>> programs_;
};

}  // namespace luxel::device
