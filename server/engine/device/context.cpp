#include "device/context.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>

#include "device/program_cache.h"

namespace luxel::device {
namespace {

std::string platform_string(cl_platform_id p, cl_platform_info what) {
  size_t n = 0;
  if (clGetPlatformInfo(p, what, 0, nullptr, &n) != CL_SUCCESS || n == 0) return {};
  std::string s(n, '\0');
  clGetPlatformInfo(p, what, n, s.data(), nullptr);
  while (!s.empty() && (s.back() == '\0' || s.back() == ' ')) s.pop_back();
  return s;
}

std::string device_string(cl_device_id d, cl_device_info what) {
  size_t n = 0;
  if (clGetDeviceInfo(d, what, 0, nullptr, &n) != CL_SUCCESS || n == 0) return {};
  std::string s(n, '\0');
  clGetDeviceInfo(d, what, n, s.data(), nullptr);
  while (!s.empty() && (s.back() == '\0' || s.back() == ' ')) s.pop_back();
  return s;
}

template <typename T>
T device_value(cl_device_id d, cl_device_info what) {
  T v{};
  clGetDeviceInfo(d, what, sizeof v, &v, nullptr);
  return v;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

}  // namespace

std::string DeviceInfo::describe() const {
  return strprintf("%s (%s, %s, driver %s, %u CUs, %.1f GiB)", device_name.c_str(),
                   platform_name.c_str(), is_gpu ? "GPU" : "CPU", driver_version.c_str(),
                   compute_units,
                   static_cast<double>(global_mem_bytes) / (1024.0 * 1024.0 * 1024.0));
}

Result<std::vector<DeviceInfo>> list_devices() {
  cl_uint np = 0;
  const cl_int err = clGetPlatformIDs(0, nullptr, &np);
  if (err == -1001 /* CL_PLATFORM_NOT_FOUND_KHR */ || np == 0)
    return unavailable("no OpenCL platform found (is an ICD such as pocl-opencl-icd installed?)");
  LUXEL_CL_RETURN_IF_ERROR(err, "clGetPlatformIDs");
  std::vector<cl_platform_id> platforms(np);
  LUXEL_CL_RETURN_IF_ERROR(clGetPlatformIDs(np, platforms.data(), nullptr), "clGetPlatformIDs");
  std::vector<DeviceInfo> out;
  for (cl_uint p = 0; p < np; ++p) {
    cl_uint nd = 0;
    if (clGetDeviceIDs(platforms[p], CL_DEVICE_TYPE_ALL, 0, nullptr, &nd) != CL_SUCCESS) continue;
    std::vector<cl_device_id> devices(nd);
    if (clGetDeviceIDs(platforms[p], CL_DEVICE_TYPE_ALL, nd, devices.data(), nullptr) != CL_SUCCESS)
      continue;
    for (cl_uint d = 0; d < nd; ++d) {
      DeviceInfo info;
      info.platform_index = static_cast<int>(p);
      info.device_index = static_cast<int>(d);
      info.platform = platforms[p];
      info.id = devices[d];
      info.platform_name = platform_string(platforms[p], CL_PLATFORM_NAME);
      info.device_name = device_string(devices[d], CL_DEVICE_NAME);
      info.vendor = device_string(devices[d], CL_DEVICE_VENDOR);
      info.device_version = device_string(devices[d], CL_DEVICE_VERSION);
      info.driver_version = device_string(devices[d], CL_DRIVER_VERSION);
      info.is_gpu =
          (device_value<cl_device_type>(devices[d], CL_DEVICE_TYPE) & CL_DEVICE_TYPE_GPU) != 0;
      info.compute_units = device_value<cl_uint>(devices[d], CL_DEVICE_MAX_COMPUTE_UNITS);
      info.global_mem_bytes = device_value<cl_ulong>(devices[d], CL_DEVICE_GLOBAL_MEM_SIZE);
      info.max_alloc_bytes = device_value<cl_ulong>(devices[d], CL_DEVICE_MAX_MEM_ALLOC_SIZE);
      info.max_work_group_size = device_value<size_t>(devices[d], CL_DEVICE_MAX_WORK_GROUP_SIZE);
      out.push_back(std::move(info));
    }
  }
  if (out.empty()) return unavailable("OpenCL platforms found, but no devices");
  return out;
}

Result<DeviceInfo> choose_device(const std::string& spec_in) {
  std::string spec = spec_in;
  std::string source = "--device";
  if (spec.empty()) {
    if (const char* env = std::getenv("LUXEL_DEVICE"); env && *env) {
      spec = env;
      source = "LUXEL_DEVICE";
    }
  }
  auto devices = list_devices();
  if (!devices) return devices.status();
  const auto& all = devices.value();
  auto listing = [&] {
    std::string s;
    for (const auto& d : all)
      s += strprintf("\n  %d:%d  %s", d.platform_index, d.device_index, d.describe().c_str());
    return s;
  };
  if (spec.empty() || spec == "default") {
    for (const auto& d : all)
      if (d.is_gpu) return d;
    return all.front();
  }
  const std::string want = lower(spec);
  if (want == "gpu" || want == "cpu") {
    for (const auto& d : all)
      if (d.is_gpu == (want == "gpu")) return d;
    return not_found(source + " '" + spec + "': no such device type; devices:" + listing());
  }
  int p = -1, d = -1;
  char tail = 0;
  if (std::sscanf(spec.c_str(), "%d:%d%c", &p, &d, &tail) == 2) {
    for (const auto& info : all)
      if (info.platform_index == p && info.device_index == d) return info;
    return not_found(source + " '" + spec +
                     "': no device with that platform:device index; devices:" + listing());
  }
  for (const auto& info : all)
    if (lower(info.device_name).find(want) != std::string::npos ||
        lower(info.platform_name).find(want) != std::string::npos)
      return info;
  return not_found(source + " '" + spec + "' matches no device; devices:" + listing());
}

Buffer& Buffer::operator=(Buffer&& o) noexcept {
  if (this != &o) {
    if (mem_) clReleaseMemObject(mem_);
    mem_ = o.mem_;
    bytes_ = o.bytes_;
    o.mem_ = nullptr;
    o.bytes_ = 0;
  }
  return *this;
}

Buffer::~Buffer() {
  if (mem_) clReleaseMemObject(mem_);
}

Kernel& Kernel::operator=(Kernel&& o) noexcept {
  if (this != &o) {
    if (k_) clReleaseKernel(k_);
    k_ = o.k_;
    name_ = std::move(o.name_);
    o.k_ = nullptr;
  }
  return *this;
}

Kernel::~Kernel() {
  if (k_) clReleaseKernel(k_);
}

Result<cl_uint> Kernel::num_args() const {
  cl_uint n = 0;
  LUXEL_RETURN_IF_ERROR(cl_status(clGetKernelInfo(k_, CL_KERNEL_NUM_ARGS, sizeof n, &n, nullptr),
                                  "kernel '" + name_ + "' argument count"));
  return n;
}

std::string Kernel::arg_what(cl_uint index) const {
  return strprintf("kernel '%s' argument %u", name_.c_str(), index);
}

Result<std::unique_ptr<Context>> Context::create(const std::string& device_spec) {
  auto chosen = choose_device(device_spec);
  if (!chosen) return chosen.status();
  std::unique_ptr<Context> ctx(new Context());
  ctx->info_ = chosen.value();
  cl_int err = CL_SUCCESS;
  const cl_context_properties props[] = {
      CL_CONTEXT_PLATFORM, reinterpret_cast<cl_context_properties>(ctx->info_.platform), 0};
  ctx->context_ = clCreateContext(props, 1, &ctx->info_.id, nullptr, nullptr, &err);
  LUXEL_CL_RETURN_IF_ERROR(err, "clCreateContext on " + ctx->info_.device_name);
  ctx->queue_ = clCreateCommandQueue(ctx->context_, ctx->info_.id, CL_QUEUE_PROFILING_ENABLE, &err);
  LUXEL_CL_RETURN_IF_ERROR(err, "clCreateCommandQueue on " + ctx->info_.device_name);
  ctx->programs_ = std::make_unique<ProgramCache>(ctx->context_, ctx->info_);
  return ctx;
}

Context::~Context() {
  if (queue_) clFinish(queue_);
  timer_.reset();
  programs_.reset();
  if (queue_) clReleaseCommandQueue(queue_);
  if (context_) clReleaseContext(context_);
}

Result<Buffer> Context::alloc(size_t bytes, const std::string& name, cl_mem_flags flags) {
  // Zero-sized buffers are invalid in OpenCL; keep one element so kernels can
  // always bind every argument of the program.
  const size_t n = std::max<size_t>(bytes, 16);
  if (n > info_.max_alloc_bytes)
    return resource_exhausted(
        strprintf("buffer '%s' needs %zu bytes, device max allocation is %llu", name.c_str(), n,
                  static_cast<unsigned long long>(info_.max_alloc_bytes)));
  cl_int err = CL_SUCCESS;
  cl_mem mem = clCreateBuffer(context_, flags, n, nullptr, &err);
  LUXEL_CL_RETURN_IF_ERROR(err, strprintf("allocating buffer '%s' (%zu bytes)", name.c_str(), n));
  return Buffer(mem, n);
}

Result<Buffer> Context::upload_bytes(const void* data, size_t bytes, const std::string& name,
                                     cl_mem_flags flags) {
  auto buf = alloc(bytes, name, flags);
  if (!buf) return buf.status();
  if (bytes > 0) LUXEL_RETURN_IF_ERROR(write(buf.value(), data, bytes));
  return buf;
}

Status Context::write(const Buffer& buffer, const void* data, size_t bytes, size_t offset) {
  return cl_status(
      clEnqueueWriteBuffer(queue_, buffer.get(), CL_TRUE, offset, bytes, data, 0, nullptr, nullptr),
      "clEnqueueWriteBuffer");
}

Status Context::read(const Buffer& buffer, void* data, size_t bytes, size_t offset) {
  return cl_status(
      clEnqueueReadBuffer(queue_, buffer.get(), CL_TRUE, offset, bytes, data, 0, nullptr, nullptr),
      "clEnqueueReadBuffer");
}

Status Context::launch(const Kernel& kernel, size_t global, size_t local, const char* label) {
  if (global == 0) return Status::ok();
  if (local > 0) global = (global + local - 1) / local * local;
  cl_event event = nullptr;
  const cl_int err = clEnqueueNDRangeKernel(queue_, kernel.get(), 1, nullptr, &global,
                                            local > 0 ? &local : nullptr, 0, nullptr, &event);
  const std::string name = label ? label : kernel.name();
  LUXEL_CL_RETURN_IF_ERROR(err, "launching kernel '" + name + "'");
  timer_.record(name, event);
  return Status::ok();
}

Status Context::finish() {
  LUXEL_CL_RETURN_IF_ERROR(clFinish(queue_), "clFinish");
  return timer_.collect();
}

}  // namespace luxel::device
