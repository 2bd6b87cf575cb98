#include "bake/bake_kernels.h"

#include <type_traits>

#include "device/program_cache.h"

namespace luxel::pipeline {
namespace {

using namespace luxel::cl;  // the element types named in bake_args.h

Status bind_buffer(device::Kernel& k, cl_uint index, const device::Buffer& b, const char* name) {
  if (!b) return internal_error(k.name() + ": buffer '" + name + "' is not allocated");
  return k.set_arg(index, b);
}

Status bind_live(device::Kernel& k, cl_uint index, const device::Buffer* b, const char* name) {
  if (!b) return internal_error(k.name() + ": no active list given for '" + name + "'");
  return bind_buffer(k, index, *b, name);
}

template <typename Expected, typename Given>
Status bind_value(device::Kernel& k, cl_uint index, const Given& v) {
  static_assert(std::is_same_v<Expected, Given>,
                "host value type differs from kernels/shared/bake_args.h");
  return k.set_arg(index, v);
}

#define LUXEL_BIND_buffer(T, name) bind_buffer(k, index++, g.name, #name)
#define LUXEL_BIND_live(T, name) bind_live(k, index++, g.name, #name)
#define LUXEL_BIND_value(T, name) bind_value<T>(k, index++, g.name)
#define LUXEL_BIND_ENTRY(kind, T, name, what) LUXEL_RETURN_IF_ERROR(LUXEL_BIND_##kind(T, name));
#define LUXEL_BIND_GROUP(access, group) \
  {                                     \
    const auto& g = args.group;         \
    LUX_GROUP_##group(LUXEL_BIND_ENTRY) \
  }
#define LUXEL_COUNT_ENTRY(kind, T, name, what) +1
#define LUXEL_COUNT_GROUP(access, group) LUX_GROUP_##group(LUXEL_COUNT_ENTRY)

// bind_<kernel>(k, args): params, then every group of the kernel's list.
#define LUXEL_DEFINE_BINDER(kernel)                                     \
  Status bind_##kernel(device::Kernel& k, const BakeKernelArgs& args) { \
    cl_uint index = 0;                                                  \
    LUXEL_RETURN_IF_ERROR(k.set_arg(index++, args.params));             \
    LUX_KERNEL_##kernel(LUXEL_BIND_GROUP) return Status::ok();          \
  }                                                                     \
  constexpr cl_uint kArgs_##kernel = 1 LUX_KERNEL_##kernel(LUXEL_COUNT_GROUP);
LUX_BAKE_KERNELS(LUXEL_DEFINE_BINDER)
#undef LUXEL_DEFINE_BINDER

}  // namespace

Result<BakeKernels> BakeKernels::create(device::Context& ctx, const device::FeatureSet& features) {
  auto program = ctx.programs().get("bake.cl", features);
  if (!program) return program.status();
  BakeKernels out;
#define LUXEL_CREATE_KERNEL(name)                              \
  {                                                            \
    auto k = program.value()->kernel(#name);                   \
    if (!k) return k.status();                                 \
    auto n = k.value().num_args();                             \
    if (!n) return n.status();                                 \
    if (n.value() != kArgs_##name)                             \
      return internal_error(                                   \
          strprintf("bake.cl kernel '%s' takes %u arguments, " \
                    "kernels/shared/bake_args.h declares %u",  \
                    #name, n.value(), kArgs_##name));          \
    out[BakeKernel::name] = std::move(k.value());              \
  }
  LUX_BAKE_KERNELS(LUXEL_CREATE_KERNEL)
#undef LUXEL_CREATE_KERNEL
  return out;
}

Status BakeKernels::bind(BakeKernel k, const BakeKernelArgs& args) {
  device::Kernel& kernel = (*this)[k];
  switch (k) {
#define LUXEL_BIND_CASE(name) \
  case BakeKernel::name:      \
    return bind_##name(kernel, args);
    LUX_BAKE_KERNELS(LUXEL_BIND_CASE)
#undef LUXEL_BIND_CASE
  }
  return internal_error("unknown bake kernel");
}

}  // namespace luxel::pipeline
