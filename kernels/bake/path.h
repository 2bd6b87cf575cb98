/* Path bookkeeping shared by the bake stages: slot ids and their octant
 * tag, the texel point as a "sensor", per-texel seeds and the independent
 * numbers for Russian roulette. Device only. */
#ifndef LUXEL_BAKE_PATH_H
#define LUXEL_BAKE_PATH_H

#include "sampling/sequence.h"
#include "sampling/warp.h"

/* Active-list entries: the path slot in the low 29 bits, the ray octant in
 * the top 3 when direction sorting is on (§5.4). */
#define LUX_TAG_SHIFT 29u
#define LUX_SLOT_MASK 0x1FFFFFFFu

/* The texel point is a "sensor" with f = 1. Irradiance keeps cosine-weighted
 * first segments (weight pi); directional encodings need radiance samples
 * uniform over the hemisphere (§3.4, "Accumulation into Linear Bases"), so
 * there the path carries radiance (weight 1) and the accumulator applies
 * 2 pi cos for irradiance. Russian roulette is relative to that weight. */
#if LUX_BASIS
#define LUX_SENSOR_PDF(cos_theta) lux_uniform_hemisphere_pdf()
#define LUX_SENSOR_WEIGHT 1.0f
#else
#define LUX_SENSOR_PDF(cos_theta) lux_cosine_hemisphere_pdf(cos_theta)
#define LUX_SENSOR_WEIGHT M_PI_F
#endif

/* An active-list entry for `slot` whose next ray goes along wi. */
inline uint lux_tag_slot(uint slot, float3 wi) {
#if LUX_SORT_DIRECTIONS
  const uint octant = (wi.x < 0.0f ? 1u : 0u) | (wi.y < 0.0f ? 2u : 0u) | (wi.z < 0.0f ? 4u : 0u);
  return slot | (octant << LUX_TAG_SHIFT);
#else
  return slot;
#endif
}

/* An independent (hash-based) uniform number for Russian roulette. The
 * padded Owen-scrambled Sobol dimensions of successive vertices are not
 * independent enough for a decision that compounds over the path: with them
 * the furnace box (albedo 0.9, 40 bounces) came out 1.7 % dark
 * (closed_form_test FurnaceBoxAtExtremeScalesAndHighAlbedo); with this, it
 * agrees. Roulette gains nothing from stratification anyway. */
inline float lux_independent_1d(uint index, uint dimension, uint seed) {
  const uint h = lux_hash_u32(lux_hash_combine(lux_hash_combine(seed, index), dimension));
  return (float)(h >> 8) * 0x1p-24f;
}

/* The covered slot of a texel (covered[] ascends), or LUX_NO_SLOT: paths
 * and state are indexed by slot, the accumulation filter's neighbours and the
 * radiance cache's hits are found by texel. */
#define LUX_NO_SLOT 0xFFFFFFFFu
inline uint lux_covered_slot(__global const uint* covered, uint n, uint texel) {
  uint lo = 0, hi = n;
  while (lo < hi) {
    const uint mid = lo + (hi - lo) / 2u;
    if (covered[mid] < texel)
      lo = mid + 1u;
    else
      hi = mid;
  }
  return lo < n && covered[lo] == texel ? lo : LUX_NO_SLOT;
}

/* Per-texel decorrelation seed of the sample sequence (§6.2). */
inline uint lux_texel_seed(uint texel, uint bake_seed) {
  return lux_hash_combine(lux_hash_u32(texel), bake_seed);
}

#endif /* LUXEL_BAKE_PATH_H */
