// Host-side layout checks for the shading structs in kernels/shared/ (the
// OpenCL C compiler lays them out the same way: float4 members, 16-byte
// aligned; int members first in LuxSky).
#include <cstddef>

#include "kernels/shared/light.h"
#include "kernels/shared/texture.h"

namespace luxel::cl {

static_assert(sizeof(LuxLight) == 80 && alignof(LuxLight) == 16);
static_assert(offsetof(LuxLight, shape) == 64);
static_assert(sizeof(LuxAliasEntry) == 16 && offsetof(LuxAliasEntry, pmf) == 8);
static_assert(sizeof(LuxSky) == 80 && alignof(LuxSky) == 16);
static_assert(offsetof(LuxSky, light) == 12 && offsetof(LuxSky, block_height) == 28 &&
              offsetof(LuxSky, normal_bins) == 32 && offsetof(LuxSky, radiance) == 48 &&
              offsetof(LuxSky, rotation) == 64);
static_assert(sizeof(LuxTexture) == 16 && offsetof(LuxTexture, flags) == 12);
static_assert(sizeof(LuxTextureSlot) == 32 && offsetof(LuxTextureSlot, texture) == 24);

}  // namespace luxel::cl
