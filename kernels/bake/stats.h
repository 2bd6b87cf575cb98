/* Stage 7, progress statistics: per work-group partial sums of the
 * relative standard error of each covered texel's mean (DESIGN.md "Accuracy
 * and error reporting"), weighted by the texel's coverage (the share of its
 * sample positions on geometry: the share of the surface its value stands
 * for, which adaptive sampling also weighs, bake/adaptive.h), the coverage
 * itself and the minimum samples per texel; the host adds the few partials
 * (the bake's error is sum(a e) / sum(a)). Relative std. error =
 * sqrt(var / n_eff) / mean with var = m2 / W and n_eff = W^2 / sum w^2. A
 * texel with fewer than 2 samples counts as 100 % error; a black texel with
 * zero variance as 0. Also the sum of the texels' mean luminance (the dark
 * floor of adaptive sampling, bake/adaptive.h). With a reference lightmap, also the squared error
 * and the relMSE term per texel. Device only. */
#ifndef LUXEL_BAKE_STATS_H
#define LUXEL_BAKE_STATS_H

#include "shared/bake_args.h"
#include "shared/sample_info.h"

/* The relative standard error of a texel's mean luminance y from its
 * Welford state (n samples, weights w = (sum w, sum w^2), m2w = M2 of the
 * luminance): sqrt(var / n_eff) / max(y, dark_floor), at most 1. Fewer than
 * 2 samples: 1; zero variance: 0; y <= 0 with variance and no floor: 1.
 * The progress statistics use dark_floor = 0; adaptive sampling a floor
 * (bake/adaptive.h). */
inline float lux_texel_rel_error(uint n, float2 w, float m2w, float y, float dark_floor) {
  if (n < 2u || !(w.x > 0.0f)) return 1.0f;
  const float var = fmax(0.0f, m2w / w.x);
  const float n_eff = w.x * w.x / fmax(w.y, 1e-30f);
  const float se = sqrt(var / n_eff);
  const float d = fmax(y, dark_floor);
  return se <= 0.0f ? 0.0f : (d > 0.0f ? fmin(se / d, 1.0f) : 1.0f);
}

/* The coverage of covered slot `slot`: the share of its texel's 64 sample
 * positions that lie on geometry (sample_offsets is per covered slot on the
 * device, raygen.h). */
inline float lux_slot_coverage(uint slot, __global const uint* sample_offsets,
                               __global const uint* sample_words) {
  return (float)lux_sample_info_count(sample_words, sample_offsets[slot]) *
         (1.0f / (float)LUX_SAMPLES_PER_TEXEL);
}

/* gid, lid, lsize, group: the work-item's ids; l_err, l_lum, l_cov, l_min, l_ref: the
 * work-group's reduction arrays (local memory, LUX_STATS_GROUP entries,
 * declared by the kernel). */
inline void lux_accum_stats(uint gid, uint lid, uint lsize, uint group, __local float* l_err,
                            __local float* l_lum, __local float* l_cov, __local uint* l_min,
                            __local float2* l_ref, LUX_STAGE_PARAMS(accum_stats)) {
  float err = 0.0f, lum = 0.0f, cov = 0.0f;
  float2 ref_err = (float2)(0.0f);
  uint t_spp = 0xFFFFFFFFu;
  if (gid < params.covered_count) {
    const uint texel = covered[gid];
    if (params.has_reference) {
      const float3 d = mean[gid].xyz - reference[texel].xyz;
      const float3 r = reference[texel].xyz;
      const float3 d2 = d * d;
      ref_err = (float2)((d2.x + d2.y + d2.z) / 3.0f,
                         (d2.x / (r.x * r.x + 1e-2f) + d2.y / (r.y * r.y + 1e-2f) +
                          d2.z / (r.z * r.z + 1e-2f)) /
                             3.0f);
    }
    /* State is per covered slot; the reference is a full image. */
    t_spp = spp[gid];
    lum = mean[gid].w;
    cov = lux_slot_coverage(gid, sample_offsets, sample_words);
    err = cov * lux_texel_rel_error(t_spp, weight[gid], m2[gid].w, lum, 0.0f);
  }
  l_err[lid] = err;
  l_lum[lid] = lum;
  l_cov[lid] = cov;
  l_min[lid] = t_spp;
  l_ref[lid] = ref_err;
  barrier(CLK_LOCAL_MEM_FENCE);
  for (uint stride = lsize / 2; stride > 0; stride >>= 1) {
    if (lid < stride) {
      l_err[lid] += l_err[lid + stride];
      l_lum[lid] += l_lum[lid + stride];
      l_cov[lid] += l_cov[lid + stride];
      l_min[lid] = min(l_min[lid], l_min[lid + stride]);
      l_ref[lid] += l_ref[lid + stride];
    }
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  if (lid == 0) {
    LuxAccumStats s;
    s.rel_error_sum = l_err[0];
    s.luminance_sum = l_lum[0];
    s.min_spp = l_min[0];
    s.coverage_sum = l_cov[0];
    s.reference = (float4)(l_ref[0], 0.0f, 0.0f);
    stats[group] = s;
  }
}

#endif /* LUXEL_BAKE_STATS_H */
