/* Material textures as the device sees them. Every texture's texels live in
 * one shared uint buffer, row 0 at the top (glTF UV (0,0) = top-left), in
 * the host's format (scene::Texture), copied as is:
 *   RGBA8 (flags without LUX_TEXTURE_FLAG_HALF): one word per texel, R in the
 *     low byte, A in the high byte. Colour textures (base colour, emissive:
 *     sRGB in the glTF file) keep their sRGB codes and are decoded to linear
 *     on fetch (LUX_TEXTURE_FLAG_SRGB); data textures (metallic-roughness)
 *     are linear. Alpha is always linear.
 *   RGBA16F (LUX_TEXTURE_FLAG_HALF): two words per texel holding four linear
 *     IEEE halves in memory order (16-bit images), read with vload_half4.
 * offset counts words.
 *
 * A material reads a texture through a LuxTextureSlot: the glTF
 * textureInfo's UV set (texCoord, or KHR_texture_transform's override), the
 * KHR_texture_transform matrix and the texture's sampler wrap modes. */
#ifndef LUXEL_SHARED_TEXTURE_H
#define LUXEL_SHARED_TEXTURE_H

#include "shared/compat.h"

#define LUX_TEXTURE_FLAG_SRGB 1 /* rgb is sRGB-encoded; decode to linear */
#define LUX_TEXTURE_FLAG_HALF 2 /* RGBA16F texels (two words each) */

/* Sampler wrap modes (glTF 2.0 §5.26 sampler.wrapS / wrapT; the modes of
 * OpenGL 4.6 §8.14.2 that glTF names). */
#define LUX_WRAP_REPEAT 0 /* 10497 */
#define LUX_WRAP_CLAMP 1  /* 33071 CLAMP_TO_EDGE */
#define LUX_WRAP_MIRROR 2 /* 33648 MIRRORED_REPEAT */

/* LuxTextureSlot.flags: bit 0 reads UV set 1 (TEXCOORD_1), bit 1 applies
 * the transform, bits 2-3 wrap S, bits 4-5 wrap T. */
#define LUX_SLOT_TEXCOORD1 1
#define LUX_SLOT_TRANSFORM 2
#define LUX_SLOT_WRAP_S(flags) (((flags) >> 2) & 3)
#define LUX_SLOT_WRAP_T(flags) (((flags) >> 4) & 3)
#define LUX_SLOT_MAKE_WRAP(s, t) (((s) << 2) | ((t) << 4))

#ifndef LUX_DEVICE
namespace luxel::cl {
#endif

typedef struct LuxTexture {
  int offset; /* first word in the shared texel buffer */
  int width;
  int height;
  int flags; /* LUX_TEXTURE_FLAG_* */
} LuxTexture;

/* One texture reference of a material, 32 bytes. The UV read is
 *   uv' = (m00 u + m01 v + m02, m10 u + m11 v + m12)
 * the KHR_texture_transform matrix T * R * S (applied only with
 * LUX_SLOT_TRANSFORM, so an untransformed texture reads uv unchanged). */
typedef struct LuxTextureSlot {
  float m00, m01, m02;
  float m10, m11, m12;
  int texture; /* index into the LuxTexture array; -1: none */
  int flags;   /* LUX_SLOT_* */
} LuxTextureSlot;

#ifndef LUX_DEVICE
}  // namespace luxel::cl
#endif

#endif /* LUXEL_SHARED_TEXTURE_H */
