/* Material textures as the device sees them: every texture's texels are
 * RGBA8 words in one shared uint buffer (R in the low byte, A in the high
 * byte), row 0 at the top (glTF UV (0,0) = top-left).
 *
 * Colour textures (base colour, emissive: sRGB in the glTF file) are stored
 * sRGB-encoded and decoded to linear on fetch; data textures (metallic-
 * roughness, normal, occlusion) are stored linear. Alpha is always linear.
 * 4 bytes per texel instead of 16 for float RGBA. */
#ifndef LUXEL_SHARED_TEXTURE_H
#define LUXEL_SHARED_TEXTURE_H

#include "shared/compat.h"

#define LUX_TEXTURE_FLAG_SRGB 1 /* rgb is sRGB-encoded; decode to linear */

#ifndef LUX_DEVICE
namespace luxel::cl {
#endif

typedef struct LuxTexture {
  int offset; /* first texel (uint index) in the shared texel buffer */
  int width;
  int height;
  int flags; /* LUX_TEXTURE_FLAG_* */
} LuxTexture;

#ifndef LUX_DEVICE
}  // namespace luxel::cl
#endif

#endif /* LUXEL_SHARED_TEXTURE_H */
