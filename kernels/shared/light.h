/* Light table and sky records shared by host and device (next-event
 * estimation, thesis §6.1; light selection by power, §6.3.2).
 *
 * UNITS. Radiometric throughout; glTF values are taken 1:1, no photometric
 * conversion:
 *   emissive triangle  radiance W/(m^2 sr) = emissiveFactor * emissive_strength
 *                      (times the emissive texture, which the caller applies)
 *   point, spot        radiant intensity W/sr = color * glTF intensity (cd)
 *   directional, sun   irradiance W/m^2 on a surface facing the light
 *                      = color * glTF intensity (lux) / bake illuminance
 *   sky                radiance = color * intensity (times the image texel)
 * glTF `range` is ignored: falloff is the physical inverse square.
 * World space is +Y up; distances are scene units.
 *
 * LuxLight: 80 bytes, five float4 named for what they hold. Integers are
 * stored as bits in float lanes; read and write those (and the overloaded
 * scalar lanes) through the LUX_LIGHT_* accessors below.
 *
 *   field        point          spot           directional       triangle (3)        sky (4)
 *   origin.xyz   position       position       -                 v0                  -
 *   origin.w     type (int)     type           type              type                type
 *   axis.xyz     -              unit direction unit direction    edge1 = v1 - v0     -
 *                               light travels  light travels
 *   axis.w       flags (int)    flags          flags             flags               flags
 *   edge2.xyz    -              -              -                 edge2 = v2 - v0     -
 *   edge2.w      -              -              -                 world triangle id   -
 *   emission.xyz intensity      intensity      irradiance E, or  radiance            mean radiance
 *                W/sr           W/sr           disc radiance                         (information)
 *                (rgb)                         E/(pi sin^2 a)
 *                                              when a > 0
 *   emission.w   -              -              -                 area                -
 *   shape.x      -              cos inner      -                 unit front normal x
 *   shape.y      -              cos outer      -                 normal y
 *   shape.z      -              -              1 - cos(a)        normal z
 *   shape.w      -              -              -                 material (int)
 *
 * "-" lanes are 0. Triangle barycentrics (LuxLightSample.bary) weigh v1 and
 * v2, like LuxHit.u/v. The triangle's front normal follows its world winding
 * (cross(edge1, edge2)), flipped for instances whose transform mirrors
 * (glTF 2.0 §3.7.4: a negative determinant reverses the winding; the same
 * rule as LuxSurfaceTri.front, which BSDF-sampled hits use). A directional light
 * with angular radius a > 0 is a disc of uniform radiance (the sun) sampled
 * over its cone of directions.
 *
 * FEATURES (-D from the FeatureSet). A type whose macro is absent is
 * compiled out: sampling it returns "no contribution".
 *   LUX_LIGHT_POINT        point lights
 *   LUX_LIGHT_SPOT         spot lights
 *   LUX_LIGHT_DIRECTIONAL  directional lights and the bake-settings sun
 *   LUX_LIGHT_EMISSIVE     emissive triangles
 *   LUX_SKY                a constant-colour sky (cosine-weighted about the
 *                          receiver's normal)
 *   LUX_SKY_IMAGE          an equirectangular sky, importance sampled
 *
 * EQUIRECT MAPPING. A world direction d is first rotated by -rotation about
 * +Y into image space l (so the image appears turned by +rotation,
 * right-handed about +Y); then
 *   u = 0.5 + atan2(l.x, -l.z) / (2 pi)     (-Z is the image centre, +X at 0.75)
 *   v = acos(l.y) / pi                      (row 0 = straight up)
 * Texels are looked up nearest (the importance-sampling distribution is
 * piecewise constant over the same texels, so pdf and radiance agree). */
#ifndef LUXEL_SHARED_LIGHT_H
#define LUXEL_SHARED_LIGHT_H

#include "shared/compat.h"

#define LUX_LIGHT_TYPE_POINT 0
#define LUX_LIGHT_TYPE_SPOT 1
#define LUX_LIGHT_TYPE_DIRECTIONAL 2
#define LUX_LIGHT_TYPE_TRIANGLE 3
#define LUX_LIGHT_TYPE_SKY 4

/* LuxLight flags (b.w). */
#define LUX_LIGHT_FLAG_DOUBLE_SIDED 1 /* emits from both faces (glTF doubleSided) */
#define LUX_LIGHT_FLAG_TEXTURED                    \
  2 /* material has an emissiveTexture: the caller \
       multiplies radiance by it */

#define LUX_SKY_KIND_NONE 0
#define LUX_SKY_KIND_CONSTANT 1
#define LUX_SKY_KIND_IMAGE 2

#ifndef LUX_DEVICE
namespace luxel::cl {
#endif

typedef struct LuxLight {
  float4 origin;
  float4 axis;
  float4 edge2;
  float4 emission;
  float4 shape;
} LuxLight;

/* Lanes with a meaning of their own (table above). Each is an lvalue where
 * it is a float, so host builders assign through them too. */
#define LUX_LIGHT_TYPE(l) lux_as_int((l).origin.w)
#define LUX_LIGHT_FLAGS(l) lux_as_int((l).axis.w)
#define LUX_LIGHT_TRIANGLE(l) lux_as_int((l).edge2.w) /* world triangle id */
#define LUX_LIGHT_AREA(l) ((l).emission.w)
#define LUX_LIGHT_COS_INNER(l) ((l).shape.x)          /* spot */
#define LUX_LIGHT_COS_OUTER(l) ((l).shape.y)          /* spot */
#define LUX_LIGHT_ONE_MINUS_COS(l) ((l).shape.z)      /* directional disc: 1 - cos(a) */
#define LUX_LIGHT_MATERIAL(l) lux_as_int((l).shape.w) /* triangle */

/* One entry of the light-selection alias table (Walker 1977; built with
 * Vose's method, IEEE TSE 17(9), 1991), 16 bytes. With u in [0, 1) and n
 * entries, cell i = floor(u n) keeps light i when the fraction u n - i is
 * below `threshold`, else it takes light `alias`: O(1) whatever n is.
 *   threshold  in [0, 1]
 *   alias      light index taken above the threshold
 *   pmf        probability that light i (this entry's own index) is chosen,
 *              computed on the host from the float thresholds exactly as the
 *              sampler realises them, so NEE and MIS read one value */
typedef struct LuxAliasEntry {
  float threshold;
  uint alias;
  float pmf;
  uint pad;
} LuxAliasEntry;

/* The sky (environment), passed to kernels by value. 80 bytes.
 *   kind        LUX_SKY_KIND_*
 *   width/height  equirect image size (0 for a constant sky)
 *   light       index of the sky's entry in the light table, -1 if none
 *   blocks_x/blocks_y, block_width/block_height  image sky: the image is cut
 *               into blocks_x x blocks_y blocks of block_width x
 *               block_height texels (the last row and column may reach past
 *               the image; those texels have weight 0)
 *   normal_bins image sky: side of the octahedral grid of receiver normals
 *   radiance    constant sky: its radiance (rgb). Image sky: the
 *               colour * intensity already multiplied into the texels
 *   rotation    x = sin, y = cos of the rotation about +Y
 * Image texels: width * height * 3 floats (rgb, radiance), row 0 = up.
 * Importance sampling (shading/sky_distribution.h), two levels:
 *   sky block cdfs  per normal cell b (normal_bins^2 of them), at
 *               b * (blocks_y + 1 + blocks_y * (blocks_x + 1)): a marginal cdf
 *               over block rows, then one conditional cdf per block row.
 *               Weights: the block's radiance mass times a bound of the
 *               cosine any normal of the cell can have with the block.
 *   sky texel cdfs  per block k = by * blocks_x + bx, at
 *               k * (block_height + 1 + block_height * (block_width + 1)):
 *               the same over the block's texels, weights luminance x
 *               sin(theta), the same for every normal. */
typedef struct LuxSky {
  int kind;
  int width;
  int height;
  int light;
  int blocks_x;
  int blocks_y;
  int block_width;
  int block_height;
  int normal_bins;
  int pad0;
  int pad1;
  int pad2;
  float4 radiance;
  float4 rotation;
} LuxSky;

#ifndef LUX_DEVICE
}  // namespace luxel::cl
#endif

#endif /* LUXEL_SHARED_LIGHT_H */
