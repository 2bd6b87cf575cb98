/* Compatibility layer: lets headers in kernels/shared/ compile both as
 * OpenCL C 1.2 (device) and as C++20 (host). Host code sees float4/int4 as
 * 16-byte aligned PODs with the same layout as cl_float4, so a struct written
 * once here has one layout on both sides (checked by static_asserts in
 * shared_layout_check.cpp). Never use float3 in a shared struct: it is 16
 * bytes in OpenCL C and 12 on the host. */
#ifndef LUXEL_SHARED_COMPAT_H
#define LUXEL_SHARED_COMPAT_H

#ifdef __OPENCL_C_VERSION__
#define LUX_DEVICE 1
#define LUX_INLINE inline
#define LUX_GLOBAL __global
#define LUX_CONSTANT __constant
#define LUX_ALIGN(n) __attribute__((aligned(n)))
#define lux_as_float(x) as_float(x)
#define lux_as_int(x) as_int(x)
#define lux_as_uint(x) as_uint(x)
#else
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#define LUX_INLINE inline
#define LUX_GLOBAL
#define LUX_CONSTANT
#define LUX_ALIGN(n) alignas(n)

namespace luxel::cl {
struct alignas(16) float4 {
  float x, y, z, w;
};
struct alignas(8) float2 {
  float x, y;
};
struct alignas(16) int4 {
  int32_t x, y, z, w;
};
struct alignas(16) uint4 {
  uint32_t x, y, z, w;
};
typedef uint32_t uint;
typedef uint64_t ulong;
inline float as_float(int32_t v) {
  return std::bit_cast<float>(v);
}
inline float as_float(uint32_t v) {
  return std::bit_cast<float>(v);
}
inline int32_t as_int(float v) {
  return std::bit_cast<int32_t>(v);
}
inline uint32_t as_uint(float v) {
  return std::bit_cast<uint32_t>(v);
}
}  // namespace luxel::cl
#define lux_as_float(x) ::luxel::cl::as_float(x)
#define lux_as_int(x) ::luxel::cl::as_int(x)
#define lux_as_uint(x) ::luxel::cl::as_uint(x)
#endif

#endif /* LUXEL_SHARED_COMPAT_H */
