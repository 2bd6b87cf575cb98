/* Alpha test for alphaMode MASK (glTF 2.0 §3.9.4): a surface point is
 * transparent when baseColorFactor.a * texture.a < alphaCutoff.
 *
 * Shared by the OpenCL traversal and by Embree's filter callback on the host,
 * so the two tracers agree bit for bit on which points are cut out. Texels are
 * 8-bit, sampled nearest with repeat wrapping (the texture's own sampler is
 * not honoured for the cut-out decision; nearest keeps the test exact and
 * cheap). */
#ifndef LUXEL_SHARED_ALPHA_MASK_H
#define LUXEL_SHARED_ALPHA_MASK_H

#include "shared/geometry.h"

#ifndef LUX_DEVICE
namespace luxel::cl {
#endif

/* True when the point with barycentrics (u, v) of triangle uvs is opaque. */
LUX_INLINE int lux_alpha_opaque(LUX_GLOBAL const LuxTriangleUV* uvs,
                                LUX_GLOBAL const LuxAlphaMask* mask,
                                LUX_GLOBAL const unsigned char* texels, float u, float v) {
  const float w = 1.0f - u - v;
  const float s = w * uvs->uv0.x + u * uvs->uv1.x + v * uvs->uv2.x;
  const float t = w * uvs->uv0.y + u * uvs->uv1.y + v * uvs->uv2.y;
  /* Wrap into [0, 1): floor keeps negative coordinates repeating correctly. */
  const float fs = s - floor(s);
  const float ft = t - floor(t);
  int x = (int)(fs * (float)mask->width);
  int y = (int)(ft * (float)mask->height);
  x = x < 0 ? 0 : (x >= mask->width ? mask->width - 1 : x);
  y = y < 0 ? 0 : (y >= mask->height ? mask->height - 1 : y);
  const float a = (float)texels[mask->offset + y * mask->width + x] * (1.0f / 255.0f);
  return a >= mask->cutoff;
}

#ifndef LUX_DEVICE
}  // namespace luxel::cl
#endif

#endif /* LUXEL_SHARED_ALPHA_MASK_H */
