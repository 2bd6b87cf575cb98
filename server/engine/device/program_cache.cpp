#include "device/program_cache.h"

#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "common/hash.h"
#include "device/kernel_sources.h"
#include "luxel_version.h"

namespace luxel::device {
namespace fs = std::filesystem;
namespace {

// Options every program gets. No fast-math: traversal must stay watertight.
constexpr const char* kBaseOptions = "-cl-std=CL1.2 -I. -DLUX_OPENCL=1";

std::string build_log(cl_program program, cl_device_id device) {
  size_t n = 0;
  clGetProgramBuildInfo(program, device, CL_PROGRAM_BUILD_LOG, 0, nullptr, &n);
  std::string log(n, '\0');
  if (n) clGetProgramBuildInfo(program, device, CL_PROGRAM_BUILD_LOG, n, log.data(), nullptr);
  while (!log.empty() && (log.back() == '\0' || log.back() == '\n')) log.pop_back();
  return log;
}

bool write_atomic(const fs::path& path, const void* data, size_t size) {
  std::error_code ec;
  fs::create_directories(path.parent_path(), ec);
  const fs::path tmp = path.string() + strprintf(".tmp%d", static_cast<int>(getpid()));
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) return false;
    f.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
    if (!f) return false;
  }
  fs::rename(tmp, path, ec);
  if (ec) fs::remove(tmp, ec);
  return !ec;
}

}  // namespace

Program::~Program() {
  if (program_) clReleaseProgram(program_);
}

Result<Kernel> Program::kernel(const std::string& name) const {
  cl_int err = CL_SUCCESS;
  cl_kernel k = clCreateKernel(program_, name.c_str(), &err);
  LUXEL_CL_RETURN_IF_ERROR(err, "clCreateKernel '" + name + "'");
  return Kernel(k, name);
}

ProgramCache::ProgramCache(cl_context context, DeviceInfo device)
    : context_(context), device_(std::move(device)) {}

std::string ProgramCache::cache_dir() {
  if (const char* d = std::getenv("LUXEL_CACHE_DIR"); d && *d) return d;
  if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x)
    return std::string(x) + "/luxel/programs";
  if (const char* h = std::getenv("HOME"); h && *h)
    return std::string(h) + "/.cache/luxel/programs";
  return "/tmp/luxel-cache/programs";
}

Result<const Program*> ProgramCache::get(const std::string& entry, const FeatureSet& features) {
  auto source = expand_kernel_source(entry);
  if (!source) return source.status();
  const std::string options = std::string(kBaseOptions) + " " + features.build_options();
  const std::string key = Hasher()
                              .add(source.value())
                              .add(options)
                              .add(device_.device_name)
                              .add(device_.device_version)
                              .add(device_.driver_version)
                              .add(device_.platform_name)
                              .add(LUXEL_VERSION)
                              .hex();
  std::lock_guard<std::mutex> lock(mutex_);
  if (auto it = programs_.find(key); it != programs_.end()) return it->second.get();

  const auto t0 = std::chrono::steady_clock::now();
  const fs::path binary_path = fs::path(cache_dir()) / (key + ".bin");
  bool from_disk = false;
  cl_program program = load_binary(binary_path.string(), options);
  if (program) {
    from_disk = true;
  } else {
    auto built = build_from_source(source.value(), options, key, entry);
    if (!built) return built.status();
    program = built.value();
    store_binary(program, binary_path.string());
  }
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  auto owned = std::make_unique<Program>(program, key, from_disk, ms);
  const Program* raw = owned.get();
  programs_.emplace(key, std::move(owned));
  return raw;
}

Result<cl_program> ProgramCache::build_from_source(const std::string& source,
                                                   const std::string& options,
                                                   const std::string& key,
                                                   const std::string& entry) {
  const char* text = source.c_str();
  const size_t len = source.size();
  cl_int err = CL_SUCCESS;
  cl_program program = clCreateProgramWithSource(context_, 1, &text, &len, &err);
  LUXEL_CL_RETURN_IF_ERROR(err, "clCreateProgramWithSource for '" + entry + "'");
  err = clBuildProgram(program, 1, &device_.id, options.c_str(), nullptr, nullptr);
  if (err == CL_SUCCESS) return program;

  const std::string log = build_log(program, device_.id);
  clReleaseProgram(program);
  const fs::path failed = fs::path(cache_dir()) / "failed";
  const fs::path src_path = failed / (key + ".cl");
  const fs::path log_path = failed / (key + ".log");
  const std::string log_file = "options: " + options + "\n" + log + "\n";
  const bool kept = write_atomic(src_path, source.data(), source.size()) &&
                    write_atomic(log_path, log_file.data(), log_file.size());
  std::string shown = log.size() > 4000 ? log.substr(0, 4000) + "\n[... truncated]" : log;
  return Status(
      StatusCode::kInternal,
      strprintf(
          "building kernel program '%s' for %s failed (%s) with options '%s'.%s\n"
          "build log:\n%s",
          entry.c_str(), device_.device_name.c_str(), cl_error_name(err).c_str(), options.c_str(),
          kept ? (" Expanded source kept at " + src_path.string() + ", log at " + log_path.string())
                     .c_str()
               : " (could not write the expanded source to the cache folder)",
          shown.c_str()));
}

cl_program ProgramCache::load_binary(const std::string& path, const std::string& options) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return nullptr;
  std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(f)),
                                   std::istreambuf_iterator<char>());
  if (bytes.empty()) return nullptr;
  const unsigned char* ptr = bytes.data();
  const size_t len = bytes.size();
  cl_int status = CL_SUCCESS, err = CL_SUCCESS;
  cl_program program =
      clCreateProgramWithBinary(context_, 1, &device_.id, &len, &ptr, &status, &err);
  if (err != CL_SUCCESS || status != CL_SUCCESS) {
    if (program) clReleaseProgram(program);
    return nullptr;  // stale or foreign binary: rebuild from source
  }
  if (clBuildProgram(program, 1, &device_.id, options.c_str(), nullptr, nullptr) != CL_SUCCESS) {
    clReleaseProgram(program);
    return nullptr;
  }
  return program;
}

void ProgramCache::store_binary(cl_program program, const std::string& path) {
  size_t size = 0;
  if (clGetProgramInfo(program, CL_PROGRAM_BINARY_SIZES, sizeof size, &size, nullptr) !=
          CL_SUCCESS ||
      size == 0)
    return;
  std::vector<unsigned char> bytes(size);
  unsigned char* ptr = bytes.data();
  if (clGetProgramInfo(program, CL_PROGRAM_BINARIES, sizeof ptr, &ptr, nullptr) != CL_SUCCESS)
    return;
  // A cache that cannot be written only costs a rebuild next time.
  write_atomic(path, bytes.data(), bytes.size());
}

}  // namespace luxel::device
