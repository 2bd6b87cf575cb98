// Host-side checks that every struct in kernels/shared/ has the layout the
// OpenCL C compiler gives it (DESIGN.md: defined once, checked on the host).
#include <cstddef>

#include "kernels/shared/geometry.h"

namespace luxel::cl {

static_assert(sizeof(float4) == 16 && alignof(float4) == 16);
static_assert(sizeof(float2) == 8 && alignof(float2) == 8);
static_assert(sizeof(LuxBvhNode) == 64 && alignof(LuxBvhNode) == 16);
static_assert(offsetof(LuxBvhNode, rmin) == 32);
static_assert(sizeof(int4) == 16 && alignof(int4) == 16);
static_assert(sizeof(LuxBvh4Node) == 128 && alignof(LuxBvh4Node) == 16);
static_assert(offsetof(LuxBvh4Node, lo_y) == 32 && offsetof(LuxBvh4Node, hi_z) == 80);
// trace_bvh4.h reads a leaf's count 4 ints after its child ref.
static_assert(offsetof(LuxBvh4Node, child) == 96 && offsetof(LuxBvh4Node, count) == 112);
static_assert(sizeof(LuxTriangle) == 48 && alignof(LuxTriangle) == 16);
static_assert(sizeof(LuxRay) == 32 && alignof(LuxRay) == 16);
static_assert(sizeof(LuxHit) == 16 && offsetof(LuxHit, prim) == 12);
static_assert(sizeof(LuxAlphaMask) == 32 && offsetof(LuxAlphaMask, wrap) == 16);
static_assert(sizeof(LuxTriangleUV) == 32 && alignof(LuxTriangleUV) == 8);

}  // namespace luxel::cl
