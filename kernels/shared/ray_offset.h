/* Robust ray-origin offsetting against self-intersection.
 *
 * Wächter and Binder, "A Fast and Robust Method for Avoiding Self-Intersection"
 * (Ray Tracing Gems, ch. 6, 2019): move the hit point along the geometric
 * normal by a fixed number of ULPs in integer space, so the offset scales with
 * the magnitude of the coordinate (large coordinates need larger offsets)
 * while staying tiny near the origin, where a small fixed float offset is used
 * instead (integer ULPs vanish near zero).
 *
 * Shared by host and device so both tracers start secondary rays from the
 * same bits. n must point to the side the new ray leaves from. */
#ifndef LUXEL_SHARED_RAY_OFFSET_H
#define LUXEL_SHARED_RAY_OFFSET_H

#include "shared/compat.h"

#define LUX_OFFSET_ORIGIN (1.0f / 32.0f)
#define LUX_OFFSET_FLOAT_SCALE (1.0f / 65536.0f)
#define LUX_OFFSET_INT_SCALE 256.0f

LUX_INLINE float lux_offset_component(float p, float n) {
  const int of_i = (int)(LUX_OFFSET_INT_SCALE * n);
  const float p_i = lux_as_float(lux_as_int(p) + ((p < 0.0f) ? -of_i : of_i));
  return (fabs(p) < LUX_OFFSET_ORIGIN) ? p + LUX_OFFSET_FLOAT_SCALE * n : p_i;
}

/* In-place offset of a point (px, py, pz) along normal (nx, ny, nz). */
#define LUX_OFFSET_RAY_ORIGIN(px, py, pz, nx, ny, nz) \
  do {                                                \
    (px) = lux_offset_component((px), (nx));          \
    (py) = lux_offset_component((py), (ny));          \
    (pz) = lux_offset_component((pz), (nz));          \
  } while (0)

#endif /* LUXEL_SHARED_RAY_OFFSET_H */
