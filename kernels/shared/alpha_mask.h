/* Alpha test for alphaMode MASK (glTF 2.0 §3.9.4): a surface point is
 * transparent when baseColorFactor.a * texture.a < alphaCutoff.
 *
 * Shared by the OpenCL traversal and by Embree's filter callback on the host,
 * so the two tracers agree bit for bit on which points are cut out. Texels are
 * 8-bit, sampled nearest (the cut-out decision ignores the sampler's
 * filters: nearest keeps the test exact and
 * cheap) with the texture sampler's wrap modes (glTF 2.0 §5.26). */
#ifndef LUXEL_SHARED_ALPHA_MASK_H
#define LUXEL_SHARED_ALPHA_MASK_H

#include "shared/geometry.h"
#include "shared/texture.h"

#ifndef LUX_DEVICE
namespace luxel::cl {
#endif

/* Nearest texel index of coordinate s on an n-texel axis under wrap `mode`
 * (OpenGL 4.6 Table 8.20 applied to floor(s n)). The coordinate is reduced
 * to one period first (floor keeps negative coordinates exact). */
LUX_INLINE int lux_alpha_texel_index(float s, int n, int mode) {
  int i;
  if (mode == LUX_WRAP_CLAMP) {
    i = (int)((s >= 0.0f ? (s < 1.0f ? s : 1.0f) : 0.0f) * (float)n);
  } else if (mode == LUX_WRAP_MIRROR) {
    const float f = s - 2.0f * floor(0.5f * s);
    i = (int)(f * (float)n);
    i = i < 0 ? 0 : (i >= 2 * n ? 2 * n - 1 : i);
    if (i >= n) i = 2 * n - 1 - i;
  } else {
    i = (int)((s - floor(s)) * (float)n);
  }
  return i < 0 ? 0 : (i >= n ? n - 1 : i);
}

/* True when the point with barycentrics (u, v) of triangle uvs is opaque. */
LUX_INLINE int lux_alpha_opaque(LUX_GLOBAL const LuxTriangleUV* uvs,
                                LUX_GLOBAL const LuxAlphaMask* mask,
                                LUX_GLOBAL const unsigned char* texels, float u, float v) {
  const float w = 1.0f - u - v;
  const float s = w * uvs->uv0.x + u * uvs->uv1.x + v * uvs->uv2.x;
  const float t = w * uvs->uv0.y + u * uvs->uv1.y + v * uvs->uv2.y;
  const int x = lux_alpha_texel_index(s, mask->width, LUX_SLOT_WRAP_S(mask->wrap));
  const int y = lux_alpha_texel_index(t, mask->height, LUX_SLOT_WRAP_T(mask->wrap));
  const float a = (float)texels[mask->offset + y * mask->width + x] * (1.0f / 255.0f);
  return a >= mask->cutoff;
}

#ifndef LUX_DEVICE
}  // namespace luxel::cl
#endif

#endif /* LUXEL_SHARED_ALPHA_MASK_H */
