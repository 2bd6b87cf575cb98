/* Per-texel sample information: which instance and triangle lies under each
 * of a texel's fixed sample positions (thesis §4.2), and its decoding on the
 * device (§4.3, Listing 4.2). Compiled as OpenCL C and as C++ (host builder,
 * tests, CPU reference), so both sides agree on every bit.
 *
 * Layout (two uint buffers):
 *   offsets[y * width + x]  first word of texel (x, y) in `words`, or
 *                           LUX_NO_SAMPLES when no sample position of the
 *                           texel lies on geometry
 *   words[offset + 0, 1]    valid mask, low then high 32 bits: bit i is set
 *                           when Hammersley point i (lux_hammersley64) of the
 *                           texel lies on at least one triangle
 *   words[offset + 2 + 4k]  record k: coverage mask low, high; instance
 *                           (index into Scene::instances); triangle (index
 *                           within that instance's mesh)
 * Records are ordered by (instance, triangle). A sample position on two
 * triangles (a shared edge, overlapping charts) is set in both records; the
 * decoder takes the first. The record count of a texel is implied: the
 * decoder stops at the first record that covers the chosen bit, and every
 * valid bit is covered by some record. */
#ifndef LUXEL_SHARED_SAMPLE_INFO_H
#define LUXEL_SHARED_SAMPLE_INFO_H

#include "shared/compat.h"

#ifndef LUX_DEVICE
#include <bit>
namespace luxel::cl {
#endif

#define LUX_SAMPLES_PER_TEXEL 64
#define LUX_NO_SAMPLES 0xFFFFFFFFu
#define LUX_SAMPLE_INFO_HEADER_WORDS 2
#define LUX_SAMPLE_INFO_RECORD_WORDS 4

#ifdef LUX_DEVICE
#define LUX_SI_FLOAT2(x, y) ((float2)((x), (y)))
#define LUX_SI_FMA(a, b, c) fma((a), (b), (c))
#else
#define LUX_SI_FLOAT2(x, y) (float2{(x), (y)})
#define LUX_SI_FMA(a, b, c) std::fma((a), (b), (c))
#endif

LUX_INLINE uint lux_popcount(uint word) {
#ifdef LUX_DEVICE
  return popcount(word);
#else
  return (uint)std::popcount(word);
#endif
}

LUX_INLINE uint lux_reverse_bits32(uint v) {
  v = ((v >> 1) & 0x55555555u) | ((v & 0x55555555u) << 1);
  v = ((v >> 2) & 0x33333333u) | ((v & 0x33333333u) << 2);
  v = ((v >> 4) & 0x0F0F0F0Fu) | ((v & 0x0F0F0F0Fu) << 4);
  v = ((v >> 8) & 0x00FF00FFu) | ((v & 0x00FF00FFu) << 8);
  return (v >> 16) | (v << 16);
}

/* Point i (0..63) of the 64-point Hammersley set [39] within a texel:
 * (i / 64, radical_inverse_base2(i)). Both coordinates are multiples of 1/64,
 * exact in float, so host and device place the samples identically. Every
 * 1/64-wide column and row of the texel holds exactly one point. */
LUX_INLINE float2 lux_hammersley64(uint i) {
  const float x = (float)i * (1.0f / 64.0f);
  const float y = (float)lux_reverse_bits32(i) * 2.3283064365386963e-10f; /* 2^-32 */
  return LUX_SI_FLOAT2(x, y);
}

/* Index (0..31) of the n-th (0-based) set bit of `word`; n < popcount(word).
 * Binary search over halves by popcount: five steps, no loop (§4.3 suggests
 * this or a lookup table [66]). */
LUX_INLINE uint lux_nth_set_bit(uint word, uint n) {
  uint index = 0u;
  uint count = lux_popcount(word & 0xFFFFu);
  if (n >= count) {
    n -= count;
    index += 16u;
    word >>= 16;
  }
  count = lux_popcount(word & 0xFFu);
  if (n >= count) {
    n -= count;
    index += 8u;
    word >>= 8;
  }
  count = lux_popcount(word & 0xFu);
  if (n >= count) {
    n -= count;
    index += 4u;
    word >>= 4;
  }
  count = lux_popcount(word & 0x3u);
  if (n >= count) {
    n -= count;
    index += 2u;
    word >>= 2;
  }
  if (n >= (word & 1u)) index += 1u;
  return index;
}

/* Number of valid sample positions of the texel whose data starts at
 * `offset` (offset != LUX_NO_SAMPLES). */
LUX_INLINE uint lux_sample_info_count(const LUX_GLOBAL uint* words, uint offset) {
  return lux_popcount(words[offset]) + lux_popcount(words[offset + 1u]);
}

/* Listing 4.2: maps `rank` in [0, lux_sample_info_count) to the rank-th valid
 * sample position of the texel at `offset` and returns the instance and mesh
 * triangle under it (the first record covering it) and its Hammersley index
 * (0..63, for lux_hammersley64). */
LUX_INLINE void lux_sample_info_lookup(const LUX_GLOBAL uint* words, uint offset, uint rank,
                                       uint* instance, uint* triangle, uint* hammersley_index) {
  const uint valid_lo = words[offset];
  const uint valid_hi = words[offset + 1u];
  const uint lo_count = lux_popcount(valid_lo);
  const uint upper = rank >= lo_count ? 1u : 0u;
  const uint bit = lux_nth_set_bit(upper ? valid_hi : valid_lo, upper ? rank - lo_count : rank);
  const uint mask = 1u << bit;
  uint record = offset + LUX_SAMPLE_INFO_HEADER_WORDS;
  while ((words[record + upper] & mask) == 0u) record += LUX_SAMPLE_INFO_RECORD_WORDS;
  *instance = words[record + 2u];
  *triangle = words[record + 3u];
  *hammersley_index = bit + 32u * upper;
}

/* a * b - c * d with one rounding error (Kahan's algorithm with fma). */
LUX_INLINE float lux_diff_of_products(float a, float b, float c, float d) {
  const float cd = c * d;
  const float err = LUX_SI_FMA(-c, d, cd);
  const float dop = LUX_SI_FMA(a, b, -cd);
  return dop + err;
}

/* Barycentric weights (of vertices 0, 1, 2) of the sample at `offset` within
 * texel (tx, ty) of a width x height atlas, for the triangle with atlas UVs
 * uv0, uv1, uv2 (row 0 at v = 0). §3.4 asks for "high-precision calculations
 * ... to avoid invalid values"; in float that means:
 *  - vertices are moved to the sample point's frame first: uv * size - texel
 *    is one fma (rounded once), so near the texel they keep their full UV
 *    precision even in an 8192^2 atlas, where uv * size alone would lose
 *    11 bits;
 *  - the three sub-triangle areas use Kahan's difference of products and are
 *    normalised by their own sum, so the weights sum to 1;
 *  - negative weights (a point that rounding put just outside, e.g. on a
 *    shared edge) are clamped to 0 before normalising, so the result always
 *    lies on the triangle. A degenerate triangle yields its centroid. */
LUX_INLINE void lux_texel_barycentrics(float2 uv0, float2 uv1, float2 uv2, float width,
                                       float height, uint tx, uint ty, float2 offset, float* w0,
                                       float* w1, float* w2) {
  const float ox = (float)tx, oy = (float)ty;
  const float ax = LUX_SI_FMA(uv0.x, width, -ox) - offset.x;
  const float ay = LUX_SI_FMA(uv0.y, height, -oy) - offset.y;
  const float bx = LUX_SI_FMA(uv1.x, width, -ox) - offset.x;
  const float by = LUX_SI_FMA(uv1.y, height, -oy) - offset.y;
  const float cx = LUX_SI_FMA(uv2.x, width, -ox) - offset.x;
  const float cy = LUX_SI_FMA(uv2.y, height, -oy) - offset.y;
  /* Twice the signed areas of (p, b, c), (p, c, a), (p, a, b), p at 0. */
  float e0 = lux_diff_of_products(bx, cy, by, cx);
  float e1 = lux_diff_of_products(cx, ay, cy, ax);
  float e2 = lux_diff_of_products(ax, by, ay, bx);
  if (e0 + e1 + e2 < 0.0f) {
    e0 = -e0;
    e1 = -e1;
    e2 = -e2;
  }
  e0 = e0 > 0.0f ? e0 : 0.0f;
  e1 = e1 > 0.0f ? e1 : 0.0f;
  e2 = e2 > 0.0f ? e2 : 0.0f;
  const float sum = e0 + e1 + e2;
  if (sum > 0.0f) {
    *w0 = e0 / sum;
    *w1 = e1 / sum;
    *w2 = e2 / sum;
  } else {
    *w0 = *w1 = *w2 = 1.0f / 3.0f;
  }
}

#ifndef LUX_DEVICE
}  // namespace luxel::cl
#endif

#endif /* LUXEL_SHARED_SAMPLE_INFO_H */
