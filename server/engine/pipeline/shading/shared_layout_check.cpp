// Host-side layout checks for the shading structs in kernels/shared/ (the
// OpenCL C compiler lays them out the same way: float4 members, 16-byte
// aligned; int members first in LuxSky).
#include <cstddef>

#include "shared/light.h"
#include "shared/texture.h"

namespace luxel::cl {

static_assert(sizeof(LuxLight) == 80 && alignof(LuxLight) == 16);
static_assert(offsetof(LuxLight, shape) == 64);
static_assert(sizeof(LuxAliasEntry) == 16 && offsetof(LuxAliasEntry, pmf) == 8);
static_assert(sizeof(LuxSky) == 48 && alignof(LuxSky) == 16);
static_assert(offsetof(LuxSky, light) == 12 && offsetof(LuxSky, radiance) == 16 &&
              offsetof(LuxSky, rotation) == 32);
static_assert(sizeof(LuxTexture) == 16 && offsetof(LuxTexture, flags) == 12);

}  // namespace luxel::cl
