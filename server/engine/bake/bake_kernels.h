// The bake program's kernels and their arguments on the host side.
//
// The argument groups and each kernel's parameter list are declared once, in
// kernels/shared/bake_args.h; this header expands the same lists into host
// structs (one member per buffer, named as in the kernels) and into one
// binder per kernel, which sets the arguments by name in declaration order.
// A host member that is missing or misnamed, or a value of the wrong type,
// fails to compile; create() also checks each kernel's argument count
// against the list, so a stale LUXEL_KERNEL_DIR source fails at start-up.
#pragma once

#include <array>

#include "common/status.h"
#include "device/context.h"
#include "device/feature_set.h"
#include "kernels/shared/bake_args.h"

namespace luxel::pipeline {

#define LUXEL_HOST_MEMBER_buffer(T, name) device::Buffer name;
#define LUXEL_HOST_MEMBER_value(T, name) cl::T name{};
#define LUXEL_HOST_MEMBER_live(T, name) const device::Buffer* name = nullptr;
#define LUXEL_HOST_MEMBER(kind, T, name, what) LUXEL_HOST_MEMBER_##kind(T, name)

// One struct per argument group of kernels/shared/bake_args.h.
struct SceneArgs {
  LUX_GROUP_scene(LUXEL_HOST_MEMBER)
};
struct LightArgs {
  LUX_GROUP_lights(LUXEL_HOST_MEMBER)
};
struct TextureArgs {
  LUX_GROUP_textures(LUXEL_HOST_MEMBER)
};
struct PathArgs {
  LUX_GROUP_paths(LUXEL_HOST_MEMBER)
};
// Which active list and live count a launch uses (they alternate per bounce).
struct LiveArgs {
  LUX_GROUP_live(LUXEL_HOST_MEMBER)
};
struct AccumArgs {
  LUX_GROUP_accum(LUXEL_HOST_MEMBER)
};
struct EncodingArgs {
  LUX_GROUP_encodings(LUXEL_HOST_MEMBER)
};
struct AllocArgs {
  LUX_GROUP_alloc(LUXEL_HOST_MEMBER)
};

#undef LUXEL_HOST_MEMBER
#undef LUXEL_HOST_MEMBER_buffer
#undef LUXEL_HOST_MEMBER_value
#undef LUXEL_HOST_MEMBER_live

// Everything a bake kernel can take. Member names are the group names of
// bake_args.h, which the binders paste together.
struct BakeKernelArgs {
  cl::LuxBakeParams params{};
  SceneArgs scene;
  LightArgs lights;
  TextureArgs textures;
  PathArgs paths;
  LiveArgs live;
  AccumArgs accum;
  EncodingArgs encodings;
  AllocArgs alloc;
};

enum class BakeKernel {
#define LUXEL_KERNEL_ENUM(k) k,
  LUX_BAKE_KERNELS(LUXEL_KERNEL_ENUM)
#undef LUXEL_KERNEL_ENUM
};

// The compiled bake.cl for one FeatureSet.
class BakeKernels {
 public:
  static Result<BakeKernels> create(device::Context& ctx, const device::FeatureSet& features);

  // Binds kernel k's arguments from `args` (by the lists of bake_args.h).
  Status bind(BakeKernel k, const BakeKernelArgs& args);
  device::Kernel& operator[](BakeKernel k) { return kernels_[static_cast<size_t>(k)]; }

 private:
#define LUXEL_KERNEL_COUNT(k) +1
  static constexpr size_t kCount = 0 LUX_BAKE_KERNELS(LUXEL_KERNEL_COUNT);
#undef LUXEL_KERNEL_COUNT
  std::array<device::Kernel, kCount> kernels_;
};

}  // namespace luxel::pipeline
