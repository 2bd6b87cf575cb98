// OpenCL device layer: device choice, context, profiling queue, RAII buffers
// and kernels, named and timed launches.
//
// Device choice, in order: the explicit spec (a --device flag), then the
// LUXEL_DEVICE environment variable, then the first GPU, else the first CPU
// device (PoCL on a machine without a GPU). A spec is "gpu", "cpu",
// "P:D" (platform and device index as `luxel devices` lists them) or a
// case-insensitive substring of the platform or device name ("pocl", "nvidia").
#pragma once

#include <CL/cl.h>

#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "common/status.h"
#include "device/cl_error.h"
#include "device/launch_timer.h"

namespace luxel::device {

struct DeviceInfo {
  int platform_index = -1, device_index = -1;
  std::string platform_name;
  std::string device_name;
  std::string vendor;
  std::string device_version;  // "OpenCL 1.2 pocl ..."
  std::string driver_version;
  bool is_gpu = false;
  unsigned compute_units = 0;
  uint64_t global_mem_bytes = 0;
  uint64_t max_alloc_bytes = 0;
  size_t max_work_group_size = 0;
  cl_device_id id = nullptr;
  cl_platform_id platform = nullptr;

  // "NVIDIA H100 (NVIDIA CUDA, driver 550.54, 132 CUs, 80 GiB)"
  std::string describe() const;
};

// Every OpenCL device on the machine, in platform/device order.
Result<std::vector<DeviceInfo>> list_devices();
// Resolves a spec (see above; "" means environment, then default).
Result<DeviceInfo> choose_device(const std::string& spec);

// Owning handle for a cl_mem. Move-only; releases on destruction.
class Buffer {
 public:
  Buffer() = default;
  Buffer(cl_mem mem, size_t bytes) : mem_(mem), bytes_(bytes) {}
  Buffer(Buffer&& o) noexcept : mem_(o.mem_), bytes_(o.bytes_) {
    o.mem_ = nullptr;
    o.bytes_ = 0;
  }
  Buffer& operator=(Buffer&& o) noexcept;
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;
  ~Buffer();

  cl_mem get() const { return mem_; }
  size_t bytes() const { return bytes_; }
  explicit operator bool() const { return mem_ != nullptr; }

 private:
  cl_mem mem_ = nullptr;
  size_t bytes_ = 0;
};

// Owning handle for a cl_kernel with typed argument setting.
class Kernel {
 public:
  Kernel() = default;
  Kernel(cl_kernel k, std::string name) : k_(k), name_(std::move(name)) {}
  Kernel(Kernel&& o) noexcept : k_(o.k_), name_(std::move(o.name_)) { o.k_ = nullptr; }
  Kernel& operator=(Kernel&& o) noexcept;
  Kernel(const Kernel&) = delete;
  Kernel& operator=(const Kernel&) = delete;
  ~Kernel();

  cl_kernel get() const { return k_; }
  const std::string& name() const { return name_; }

  // set_args(a, b, c): Buffer arguments pass their cl_mem, trivially
  // copyable values pass by value; a null Buffer passes a null cl_mem.
  template <typename... Args>
  Status set_args(const Args&... args) {
    cl_uint index = 0;
    Status st;
    ((st.is_ok() ? (void)(st = set_arg(index++, args)) : (void)0), ...);
    return st;
  }

  // One argument: a Buffer passes its cl_mem, a trivially copyable value by
  // value.
  Status set_arg(cl_uint index, const Buffer& b) {
    cl_mem m = b.get();
    return cl_status(clSetKernelArg(k_, index, sizeof m, &m), arg_what(index));
  }
  template <typename T>
  requires std::is_trivially_copyable_v<T> Status set_arg(cl_uint index, const T& v) {
    return cl_status(clSetKernelArg(k_, index, sizeof v, &v), arg_what(index));
  }
  // The kernel's parameter count (CL_KERNEL_NUM_ARGS).
  Result<cl_uint> num_args() const;

 private:
  std::string arg_what(cl_uint index) const;

  cl_kernel k_ = nullptr;
  std::string name_;
};

class ProgramCache;

class Context {
 public:
  // Creates a context and an in-order profiling queue on the chosen device.
  static Result<std::unique_ptr<Context>> create(const std::string& device_spec = "");
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  const DeviceInfo& info() const { return info_; }
  cl_context context() const { return context_; }
  cl_command_queue queue() const { return queue_; }
  ProgramCache& programs() { return *programs_; }
  LaunchTimer& timer() { return timer_; }

  // Allocates a device buffer; name appears in the error if it fails.
  Result<Buffer> alloc(size_t bytes, const std::string& name,
                       cl_mem_flags flags = CL_MEM_READ_WRITE);
  // Allocates and uploads host data (blocking).
  template <typename T>
  Result<Buffer> upload(const std::vector<T>& data, const std::string& name,
                        cl_mem_flags flags = CL_MEM_READ_ONLY) {
    return upload_bytes(data.data(), data.size() * sizeof(T), name, flags);
  }
  Result<Buffer> upload_bytes(const void* data, size_t bytes, const std::string& name,
                              cl_mem_flags flags = CL_MEM_READ_ONLY);
  Status write(const Buffer& buffer, const void* data, size_t bytes, size_t offset = 0);
  Status read(const Buffer& buffer, void* data, size_t bytes, size_t offset = 0);
  template <typename T>
  Status read(const Buffer& buffer, std::vector<T>& out) {
    return read(buffer, out.data(), out.size() * sizeof(T));
  }

  // Enqueues a 1-D launch of `global` work-items, rounded up to a multiple of
  // `local` (0: the driver chooses). The launch is recorded under the kernel's
  // name (or `label`) in timer() once the queue has finished.
  Status launch(const Kernel& kernel, size_t global, size_t local = 0, const char* label = nullptr);
  Status finish();

 private:
  Context() = default;
  DeviceInfo info_;
  cl_context context_ = nullptr;
  cl_command_queue queue_ = nullptr;
  std::unique_ptr<ProgramCache> programs_;
  LaunchTimer timer_;
};

}  // namespace luxel::device
