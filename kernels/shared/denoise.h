/* Parameters of the edge-avoiding a-trous lightmap denoiser (kernels/denoise.cl),
 * shared by host and device. Per texel the kernels read the guides that
 * server/engine/post/denoise_guides.h builds:
 *   position  float4: world position (xyz) and w = world length of one
 *             texel's side there (0: texel not covered, never read or written)
 *   normal    float4: unit shading normal (xyz), w unused
 *   chart     uint: chart id (texels of different charts never mix) */
#ifndef LUXEL_SHARED_DENOISE_H
#define LUXEL_SHARED_DENOISE_H

#include "shared/compat.h"

#ifndef LUX_DEVICE
namespace luxel::cl {
#endif

/* One a-trous iteration, 32 bytes. */
typedef struct LuxDenoiseParams {
  int width, height; /* texels of the (stacked) lightmap */
  int step;          /* tap spacing of this iteration: 1, 2, 4, ... */
  /* Edge-stopping (after Schied et al. 2017, §4.4): luminance difference in
   * units of sigma_luminance x the two texels' joint standard error; normal
   * weight max(0, n.n')^sigma_normal; distance from the centre texel's
   * tangent plane in units of sigma_plane texel sides. */
  float sigma_luminance;
  float sigma_normal;
  float sigma_plane;
  int pad0, pad1;
} LuxDenoiseParams;

#ifndef LUX_DEVICE
}  // namespace luxel::cl
#endif

#endif /* LUXEL_SHARED_DENOISE_H */
