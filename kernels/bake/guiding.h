/* First-bounce guiding per texel (LUX_GUIDING): each texel learns, from its
 * own earlier iterations, where the light of its first bounce comes from,
 * and draws its first direction from a mixture of that distribution and the
 * cosine lobe. Irradiance lightmaps only (directional encodings weight their
 * samples as uniform over the hemisphere). Device only.
 *
 * The distribution is a 4 x 4 histogram over the square (u1, u2) of the
 * cosine-weighted map
 *   z = sqrt(1 - u1),  r = sqrt(u1),  phi = 2 pi u2,
 * whose bins have equal projected solid angle. Bin k holds the sum over the
 * texel's earlier paths through it of luminance(L) cos / p, the path's
 * indirect irradiance estimate without the texel point's light sample
 * (NEE already samples the lights), over pi: an estimate of the integral of
 * the incident luminance over the bin's part of the square, whatever
 * distribution the directions were drawn from (the 1/p makes it so). The
 * guided density in the square is then 16 P_k, P_k = h_k / sum h.
 *
 * The first direction is drawn from the one-sample mixture (Veach's
 * one-sample MIS, thesis §2.4's balance heuristic with one sample from the
 * chosen strategy):
 *   p(w) = cos / pi * m(w),   m(w) = (1 - a) + a 16 P_k(w),   a = LUX_GUIDE_SHARE,
 * and weighted cos / p = pi / m(w), so every direction keeps p > 0 where
 * cos > 0 and the estimate stays unbiased with any histogram; a bad one
 * costs at most 1 / (1 - a) = 4/3 the variance. NEE at the texel point is MIS-
 * weighted against the same p (lux_guide_factor in scatter.h), and so are
 * emitters and the sky that the first segment hits (path.throughput.w).
 *
 * Epochs, or why the guide is not updated continuously: a density learned
 * from a texel's earlier samples and used with later points of the same
 * scrambled Sobol sequence is not an unbiased scheme, since later points
 * are placed relative to earlier ones (stratification) and the weights
 * cos / p then correlate with them: the guided furnace box read 1.6 %
 * bright that way, and exact with independent random numbers. So a texel's
 * samples come in epochs of doubling length (indices [0, 16), [16, 32),
 * [32, 64), ...), each with its own scramble seed (a fresh, independent
 * Owen scrambling of the same net; epoch 0 keeps the texel's seed), and the
 * guide that samples in epoch e use holds only epochs before e: accumulate
 * splats into `current`, for paths of the texel's current epoch, and adds
 * `current` into `frozen` when the texel's sample count passes the epoch's
 * end. Raygen samples from `frozen` alone. Paths of the next epoch traced in
 * the same iteration (the batch straddles the boundary) teach nothing.
 *
 * Determinism: the histograms are read as the earlier iterations left them
 * and written by accumulate for the texel's own paths, in slot order. They
 * are part of the checkpoint, so a resumed bake gives the same bits; tiles
 * learn their own texels; each shard learns from its own samples (its
 * estimate is unbiased, so shards still merge exactly by their sums). The
 * first epoch, with an empty guide, draws exactly the cosine samples of an
 * unguided bake. */
#ifndef LUXEL_BAKE_GUIDING_H
#define LUXEL_BAKE_GUIDING_H

#include "sampling/sequence.h"
#include "sampling/warp.h"
#include "shading/bsdf.h"
#include "shared/bake.h"

#if LUX_GUIDING && (LUX_BASIS || LUX_PROBES)
#error "first-bounce guiding is for irradiance lightmaps"
#endif

/* LUX_GUIDE_BINS = LUX_GUIDE_SIDE^2 bins; per texel LUX_GUIDE_STRIDE
 * float4 (kernels/shared/bake.h): the frozen histogram (what raygen samples
 * from), then the current epoch's. */
#define LUX_GUIDE_SIDE 4
#define LUX_GUIDE_HALF (LUX_GUIDE_STRIDE / 2)
/* Samples in the first epoch; each later epoch doubles. */
#define LUX_GUIDE_FIRST_EPOCH 16u

/* The epoch of a texel's sample index: 0 for [0, 16), e for
 * [16 2^(e-1), 16 2^e). */
inline uint lux_guide_epoch(uint index) {
  const uint q = index / LUX_GUIDE_FIRST_EPOCH;
  return q == 0u ? 0u : 32u - clz(q);
}

/* The scramble seed of a sample in epoch e: independent per epoch. */
inline uint lux_guide_seed(uint seed, uint index) {
  const uint e = lux_guide_epoch(index);
  return e == 0u ? seed : lux_hash_combine(seed, 0x9E3779B9u + e);
}
/* The guided strategy's share of the mixture. At 0.5 the Cornell box and
 * the breakfast room came out worse at equal time than at 0.25
 * (docs/accuracy.md "First-bounce guiding"). */
#define LUX_GUIDE_SHARE 0.25f
/* The first epoch that samples from the guide (from sample 32 on): a
 * histogram of 16 samples is mostly noise, and its weights pi / m add
 * variance. */
#define LUX_GUIDE_FIRST_GUIDED_EPOCH 2u

/* The histogram bin of a local direction (z up; z > 0). */
inline uint lux_guide_bin(float3 w) {
  const float u1 = clamp(1.0f - w.z * w.z, 0.0f, 0.99999994f);
  float u2 = atan2(w.y, w.x) * (0.5f * LUX_INV_PI);
  if (u2 < 0.0f) u2 += 1.0f;
  u2 = clamp(u2, 0.0f, 0.99999994f);
  /* A non-finite direction (a degenerate frame) must still name a bin: the
   * index is written through in lux_guide_learn. */
  if (!(u1 >= 0.0f && u2 >= 0.0f)) return 0u;
  return min((uint)(u1 * LUX_GUIDE_SIDE), LUX_GUIDE_SIDE - 1u) * LUX_GUIDE_SIDE +
         min((uint)(u2 * LUX_GUIDE_SIDE), LUX_GUIDE_SIDE - 1u);
}

inline float lux_guide_value(__global const float4* h, uint k) {
  const float4 v = h[k >> 2];
  const uint i = k & 3u;
  return i == 0u ? v.x : (i == 1u ? v.y : (i == 2u ? v.z : v.w));
}

inline float lux_guide_total(__global const float4* h) {
  float s = 0.0f;
  for (uint i = 0; i < LUX_GUIDE_HALF; ++i) s += h[i].x + h[i].y + h[i].z + h[i].w;
  return s;
}

/* m(w) of the mixture: the density relative to the cosine lobe's. 1 while
 * the histogram is empty (the first iteration traces the cosine lobe). */
inline float lux_guide_factor(__global const float4* h, float total, float3 w) {
  if (!(total > 0.0f)) return 1.0f;
  return (1.0f - LUX_GUIDE_SHARE) +
         LUX_GUIDE_SHARE * (float)LUX_GUIDE_BINS * lux_guide_value(h, lux_guide_bin(w)) / total;
}

/* The first direction (local, z up): with probability LUX_GUIDE_SHARE (u_s)
 * a bin by its share of the histogram (u_s rescaled) and a point in it
 * (u), else the cosine lobe at u. */
inline float3 lux_guide_sample(__global const float4* h, float total, float u_s, float2 u) {
  if (!(total > 0.0f) || u_s >= LUX_GUIDE_SHARE) return lux_cosine_hemisphere(u);
  const float target = (u_s / LUX_GUIDE_SHARE) * total;
  uint k = 0;
  float acc = 0.0f;
  for (; k < LUX_GUIDE_BINS - 1u; ++k) {
    const float v = lux_guide_value(h, k);
    if (v > 0.0f && target < acc + v) break;
    acc += v;
  }
  /* Rounding can leave target past the sum: the last non-empty bin. */
  while (k > 0u && !(lux_guide_value(h, k) > 0.0f)) --k;
  const float u1 = ((float)(k / LUX_GUIDE_SIDE) + u.x) * (1.0f / LUX_GUIDE_SIDE);
  const float u2 = ((float)(k % LUX_GUIDE_SIDE) + u.y) * (1.0f / LUX_GUIDE_SIDE);
  const float r = sqrt(u1);
  const float2 cs = lux_cos_sin_2pi(u2);
  return (float3)(r * cs.x, r * cs.y, sqrt(fmax(0.0f, 1.0f - u1)));
}

/* One texel's learning after an iteration (accumulate.h): its own paths
 * [first, end) of the path buffer, `next` = the global index of its next
 * sample. Each path of the current epoch (that of the first path) splats
 * the luminance of cos L / p over pi, its irradiance without the texel
 * point's light sample, into its first direction's bin of `current`; when
 * `next` starts a later epoch, `current` joins `frozen`. */
inline void lux_guide_learn(__global float4* h, __global const LuxPath* paths, uint first, uint end,
                            uint next) {
  if (first >= end) return;
  const uint epoch = lux_guide_epoch(paths[first].sample_index);
  __global float* current = (__global float*)(h + LUX_GUIDE_HALF);
  for (uint p = first; p < end; ++p) {
    const LuxPath path = paths[p];
    if (lux_guide_epoch(path.sample_index) != epoch) continue; /* teaches nothing */
    const float e = (lux_luminance(path.radiance.xyz) - path.prev_normal.w) * LUX_INV_PI;
    if (path.prev_pos.w >= 0.0f && path.prev_pos.w < (float)LUX_GUIDE_BINS && isfinite(e) &&
        e > 0.0f)
      current[(uint)path.prev_pos.w] += e;
  }
  if (lux_guide_epoch(next) == epoch) return;
  for (uint i = 0; i < LUX_GUIDE_HALF; ++i) {
    h[i] += h[LUX_GUIDE_HALF + i];
    h[LUX_GUIDE_HALF + i] = (float4)(0.0f);
  }
}

#endif /* LUXEL_BAKE_GUIDING_H */
