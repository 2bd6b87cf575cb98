#include "bake/primitives/tile_shape.h"

#include "device/feature_set.h"
#include "device/program_cache.h"

namespace luxel::pipeline {
namespace {

bool is_power_of_two(size_t n) {
  return n != 0 && (n & (n - 1)) == 0;
}

// Why `kernel` cannot run with `group_size` work-items, or "" when it can.
std::string unfit_reason(const device::Context& ctx, const device::Kernel& kernel,
                         size_t group_size) {
  size_t max_group = 0;
  cl_ulong local_bytes = 0, device_local = 0;
  const cl_device_id dev = ctx.info().id;
  if (clGetKernelWorkGroupInfo(kernel.get(), dev, CL_KERNEL_WORK_GROUP_SIZE, sizeof max_group,
                               &max_group, nullptr) == CL_SUCCESS &&
      max_group < group_size)
    return strprintf("kernel '%s' runs at most %zu work-items per group", kernel.name().c_str(),
                     max_group);
  if (clGetKernelWorkGroupInfo(kernel.get(), dev, CL_KERNEL_LOCAL_MEM_SIZE, sizeof local_bytes,
                               &local_bytes, nullptr) == CL_SUCCESS &&
      clGetDeviceInfo(dev, CL_DEVICE_LOCAL_MEM_SIZE, sizeof device_local, &device_local, nullptr) ==
          CL_SUCCESS &&
      local_bytes > device_local)
    return strprintf("kernel '%s' needs %llu bytes of local memory, the device has %llu",
                     kernel.name().c_str(), static_cast<unsigned long long>(local_bytes),
                     static_cast<unsigned long long>(device_local));
  return {};
}

}  // namespace

size_t TileShape::groups_for(size_t capacity) const {
  const size_t t = tile();
  return capacity == 0 ? 1 : (capacity + t - 1) / t;
}

bool TileShape::valid() const {
  return is_power_of_two(group_size) && items_per_item > 0 && tile() <= (size_t{1} << 20);
}

std::string TileShape::describe() const {
  return strprintf("%zux%zu%s", group_size, items_per_item, local_reorder ? ", local reorder" : "");
}

TileShape preferred_tile_shape(const device::DeviceInfo& device) {
  TileShape shape = device.is_gpu ? TileShape{128, 8, true} : TileShape{1, 4096, false};
  while (shape.group_size > 1 && shape.group_size > device.max_work_group_size)
    shape.group_size /= 2;
  return shape;
}

Result<TiledKernels> build_tiled_kernels(device::Context& ctx, const std::string& entry,
                                         const std::vector<std::string>& kernel_names,
                                         TileShape shape) {
  if (shape.group_size == 0) shape = preferred_tile_shape(ctx.info());
  if (!shape.valid())
    return invalid_argument(
        strprintf("tile shape %s for '%s': the work-group size must be a "
                  "power of two and the tile at most 2^20 elements",
                  shape.describe().c_str(), entry.c_str()));
  std::string why_smaller;
  for (; shape.group_size >= 1; shape.group_size /= 2) {
    device::FeatureSet features;
    features.set(device::Feature::PRIM_WG, static_cast<int>(shape.group_size))
        .set(device::Feature::PRIM_ITEMS, static_cast<int>(shape.items_per_item))
        .set(device::Feature::PRIM_LOCAL_REORDER, shape.local_reorder ? 1 : 0);
    auto program = ctx.programs().get(entry, features);
    if (!program) return program.status();
    TiledKernels out{shape, {}};
    std::string reason;
    for (const auto& name : kernel_names) {
      auto kernel = program.value()->kernel(name);
      if (!kernel) return kernel.status();
      reason = unfit_reason(ctx, kernel.value(), shape.group_size);
      if (!reason.empty()) break;
      out.kernels.push_back(std::move(kernel.value()));
    }
    if (reason.empty()) return out;
    why_smaller = reason;
  }
  return unavailable(strprintf("'%s' cannot run on %s with any work-group size: %s", entry.c_str(),
                               ctx.info().device_name.c_str(), why_smaller.c_str()));
}

}  // namespace luxel::pipeline
