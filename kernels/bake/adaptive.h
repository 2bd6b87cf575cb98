/* Adaptive sampling (thesis §3.3, "Variance-Based Adaptive Sampling"): the
 * texel domain of an adaptive iteration. Instead of every covered texel
 * taking the same share of the iteration's paths (bake/texel_domain.h),
 * texel c takes a share proportional to an integer weight q_c computed from
 * its accumulated state:
 *
 *   alloc_weights  per slot: q_c = round(min(e_c * scale, cap) + mix), and
 *                  per block of LUX_ALLOC_GROUP slots the sum of q
 *   alloc_scan     one work-group: exclusive scan of the block sums (the
 *                  blocks' first CDF value), the total T after the last
 *   alloc_keys     per slot: its CDF value P_c (block offset + local scan),
 *                  and the keys of path slots [floor(B P_c / T),
 *                  floor(B P_{c+1} / T)) = c, B = the iteration's paths
 *
 * Every texel thus gets floor or ceil of its share B q_c / T and the counts
 * sum to B exactly (the scan-based form of the CDF sampling of §3.3, without
 * random numbers or a binary search per path). The keys come out sorted, so
 * the radix sort is skipped and the offset buffer (Listing 3.1) is built
 * from them directly. All arithmetic after q_c is integer, and q_c depends
 * only on the texel's state: the allocation, like the bake, is a function
 * of the seed and settings alone.
 *
 * e_c is the relative standard error of the texel's mean luminance with a
 * dark floor: sqrt(var / n_eff) / max(y, alloc_floor), at most 1 (stats.h),
 * and its term is weighted by the texel's coverage a_c, the share of its 64
 * sample positions on geometry (lux_slot_coverage).
 * Why this weight: the bake's error estimate and target_error are the mean
 * of e over texels weighted by coverage (stats.h). A texel with per-sample
 * relative deviation r has e = r / sqrt(n); giving each batch in proportion
 * to a e reaches the fixed point n_c ~ (a_c r_c)^(2/3) (then a_c e_c ~ n_c
 * and the shares keep the ratios), which is exactly the allocation
 * minimising sum_c a_c r_c / sqrt(n_c) under sum_c n_c = N (Lagrange:
 * a_c r_c n_c^(-3/2) constant). The coverage weight spends samples by what
 * a texel stands for: a chart's border texel that is a fifth on geometry
 * covers a fifth of the surface of an inner one, and a renderer's bilinear
 * fetch reads it over about that share of the surface, so its error counts
 * that much. What the texel means is unchanged (the mean over its covered
 * part, §4.2); only its noise grows, as (1 / a)^(1/3) at the fixed point.
 * Equalising e instead (n ~ r^2) would pour samples into the few hardest
 * texels; weighting by variance alone (absolute error) would ignore that a
 * lightmap is viewed after tone mapping, where relative error is what
 * shows. The dark floor
 * (the host sets it to the tile's mean luminance: texels darker than the
 * mean are weighed by absolute error in units of the mean, brighter ones by
 * relative error) stops dark texels, whose relative error is large but
 * whose absolute error is small, from soaking up samples; the cap
 * at 1 (100 %) bounds any one texel. The defensive term `mix` (a fraction of
 * the mean error) keeps every texel sampled each iteration: an estimate
 * that is wrongly low (all samples so far zero: e = 0) still gets samples,
 * so every texel's count grows without bound and the bake stays consistent
 * (the bias of adaptive sampling noted by Kirk and Arvo, §3.3, vanishes as
 * n grows). Device only; compiled in with LUX_ADAPTIVE. */
#ifndef LUXEL_BAKE_ADAPTIVE_H
#define LUXEL_BAKE_ADAPTIVE_H

#include "bake/stats.h"
#include "shared/bake_args.h"

#if LUX_ADAPTIVE

inline uint lux_alloc_blocks(uint covered) {
  return (covered + LUX_ALLOC_GROUP - 1u) / LUX_ALLOC_GROUP;
}

/* l_q: LUX_ALLOC_GROUP entries of local memory. */
inline void lux_alloc_weights(uint gid, uint lid, uint group, __local uint* l_q,
                              LUX_STAGE_PARAMS(alloc_weights)) {
  uint q = 0;
  if (gid < params.covered_count) {
    const float e =
        lux_texel_rel_error(spp[gid], weight[gid], m2[gid].w, mean[gid].w, params.alloc_floor);
    const float coverage = lux_slot_coverage(gid, sample_offsets, sample_words);
    q = (uint)(fmin(e * params.alloc_scale, params.alloc_cap) * coverage + params.alloc_mix + 0.5f);
    alloc_weights[gid] = q;
  }
  l_q[lid] = q;
  barrier(CLK_LOCAL_MEM_FENCE);
  for (uint stride = LUX_ALLOC_GROUP / 2u; stride > 0; stride >>= 1) {
    if (lid < stride) l_q[lid] += l_q[lid + stride];
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  if (lid == 0) alloc_blocks[group] = (ulong)l_q[0];
}

/* One work-group of LUX_ALLOC_GROUP items (l_s: as many ulong): each item
 * sums a contiguous run of block sums, a local scan gives the runs' offsets,
 * and each item writes its blocks' exclusive offsets; the last writes the
 * total after the last block. Integer: exact and order-independent. */
inline void lux_alloc_scan(uint lid, __local ulong* l_s, LUX_STAGE_PARAMS(alloc_scan)) {
  const uint blocks = lux_alloc_blocks(params.covered_count);
  const uint per = (blocks + LUX_ALLOC_GROUP - 1u) / LUX_ALLOC_GROUP;
  const uint b0 = min(lid * per, blocks), b1 = min(b0 + per, blocks);
  ulong sum = 0;
  for (uint b = b0; b < b1; ++b) sum += alloc_blocks[b];
  l_s[lid] = sum;
  barrier(CLK_LOCAL_MEM_FENCE);
  for (uint stride = 1; stride < LUX_ALLOC_GROUP; stride <<= 1) {
    const ulong add = lid >= stride ? l_s[lid - stride] : 0ul;
    barrier(CLK_LOCAL_MEM_FENCE);
    l_s[lid] += add;
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  ulong run = l_s[lid] - sum;
  for (uint b = b0; b < b1; ++b) {
    const ulong s = alloc_blocks[b];
    alloc_blocks[b] = run;
    run += s;
  }
  if (lid == LUX_ALLOC_GROUP - 1u) alloc_blocks[blocks] = l_s[lid];
}

/* l_q: LUX_ALLOC_GROUP entries of local memory. The host bounds the weights
 * so that paths * T < 2^64 (no overflow in B * P). */
inline void lux_alloc_keys(uint gid, uint lid, uint group, __local uint* l_q,
                           LUX_STAGE_PARAMS(alloc_keys)) {
  const uint q = gid < params.covered_count ? alloc_weights[gid] : 0u;
  /* Inclusive scan in the work-group (Hillis-Steele), integer: exact. */
  l_q[lid] = q;
  barrier(CLK_LOCAL_MEM_FENCE);
  for (uint stride = 1; stride < LUX_ALLOC_GROUP; stride <<= 1) {
    const uint add = lid >= stride ? l_q[lid - stride] : 0u;
    barrier(CLK_LOCAL_MEM_FENCE);
    l_q[lid] += add;
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  if (gid >= params.covered_count) return;
  const ulong total = alloc_blocks[lux_alloc_blocks(params.covered_count)];
  const ulong p_end = alloc_blocks[group] + (ulong)l_q[lid];
  const ulong p_begin = p_end - (ulong)q;
  const ulong b = (ulong)params.paths;
  const uint first = (uint)(b * p_begin / total);
  const uint end = (uint)(b * p_end / total);
  for (uint k = first; k < end; ++k) keys[k] = gid;
}

#endif /* LUX_ADAPTIVE */

#endif /* LUXEL_BAKE_ADAPTIVE_H */
