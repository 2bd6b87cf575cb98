// Host/device layout agreement for the bake structs (kernels/shared/bake.h).
#include <cstddef>

#include "kernels/shared/bake.h"
#include "shards/checkpoint.h"

namespace luxel::cl {
static_assert(sizeof(LuxSurfaceTri) == 128 && alignof(LuxSurfaceTri) == 16);
static_assert(offsetof(LuxSurfaceTri, uv0) == 96);
static_assert(offsetof(LuxSurfaceTri, front) == 120);
static_assert(sizeof(LuxTriangleTangents) == 48 && alignof(LuxTriangleTangents) == 16);
static_assert(sizeof(LuxMaterial) == 208 && alignof(LuxMaterial) == 16);
static_assert(offsetof(LuxMaterial, specular) == 32 && offsetof(LuxMaterial, metallic) == 48);
static_assert(offsetof(LuxMaterial, base_color_tex) == 64 &&
              offsetof(LuxMaterial, emissive_tex) == 128);
static_assert(offsetof(LuxMaterial, normal_tex) == 160 &&
              offsetof(LuxMaterial, normal_scale) == 192);
static_assert(sizeof(LuxPath) == 112);
static_assert(LUX_GUIDE_STRIDE == luxel::pipeline::kGuideStride);
static_assert(offsetof(LuxPath, texel) == 80 && offsetof(LuxPath, sample_pos) == 96);
static_assert(sizeof(LuxBakeParams) == 104 && alignof(LuxBakeParams) == 8);
static_assert(offsetof(LuxBakeParams, first_path) == 48 &&
              offsetof(LuxBakeParams, adaptive_pass) == 76 &&
              offsetof(LuxBakeParams, alloc_mix) == 88 &&
              offsetof(LuxBakeParams, shard_count) == 100);
static_assert(sizeof(LuxAccumStats) == 32);
static_assert(sizeof(LuxBasisSample) == 80 && alignof(LuxBasisSample) == 16);
static_assert(sizeof(LuxEncoding) == 32 && offsetof(LuxEncoding, sharpness) == 28);
}  // namespace luxel::cl
