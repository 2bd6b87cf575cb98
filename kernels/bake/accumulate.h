/* Stage 6, gather accumulation (thesis §3.2.2, Listing 3.2): one
 * work-item per covered texel gathers its paths through the offset buffer.
 * Device only. */
#ifndef LUXEL_BAKE_ACCUMULATE_H
#define LUXEL_BAKE_ACCUMULATE_H

#include "bake/guiding.h"
#include "bake/radiance_cache.h"
#include "bake/scatter.h"
#include "primitives/offset_buffer.h"
#include "shared/bake_args.h"
#include "shared/shard.h"
#if LUX_BASIS
#include "bake/basis.h"
#endif
#include "shared/probe.h"

/* One work-item per covered texel: exclusive access, so the running mean and
 * variance use Welford's algorithm (weighted form, West 1979) without atomics.
 * mean.w / m2.w track luminance, whose variance gives the error estimate.
 * weight = (sum w, sum w^2); spp counts the texel's own paths (box sense),
 * which also advances its sample sequence. A non-finite sample is dropped and
 * counted, never accumulated. */
inline float lux_filter_weight(float2 d) {
#if LUX_FILTER_GAUSSIAN
  /* PBRT's truncated Gaussian, radius 1.5 texels, alpha 2, separable. */
  const float r = 1.5f, alpha = 2.0f;
  const float edge = exp(-alpha * r * r);
  const float wx = fmax(0.0f, exp(-alpha * d.x * d.x) - edge);
  const float wy = fmax(0.0f, exp(-alpha * d.y * d.y) - edge);
  return wx * wy;
#else
  return 1.0f;
#endif
}

inline void lux_welford(float4 x, float w, float4* mean, float4* m2, float2* weight) {
  const float w_new = (*weight).x + w;
  const float4 delta = x - *mean;
  *mean += delta * (w / w_new);
  *m2 += w * delta * (x - *mean);
  *weight = (float2)(w_new, (*weight).y + w * w);
}

/* One path's sample for the accumulator: its irradiance estimate and, in
 * basis mode, the radiance along its first segment (l) and the texel point's
 * light sample (nee, visibility applied). 0 when non-finite (dropped). The
 * firefly clamp scales all three alike. */
inline int lux_path_sample_of(float3 radiance, __global const LuxBasisSample* basis_samples, uint p,
                              float clamp_luminance, float3* irradiance, float3* l, float3* nee) {
  *l = radiance;
#if LUX_BASIS
  const LuxBasisSample bs = basis_samples[p];
  *nee = bs.nee.xyz * bs.nee.w;
#if LUX_PROBES
  /* A probe's scalar irradiance (the integral of L over the sphere, the
   * L0 moment times sqrt(4 pi)): the figure its error estimate follows. */
  *irradiance = *l * LUX_BASIS_MEASURE + *nee * LUX_BASIS_NEE_SCALE;
#else
  *irradiance = *l * (LUX_TWO_PI_F * bs.dir_world.w) + *nee * fmax(bs.nee_world.w, 0.0f);
#endif
  if (!lux_finite3(*irradiance) || !lux_finite3(*nee)) return 0;
#else
  *nee = (float3)(0.0f);
  *irradiance = *l;
  if (!lux_finite3(*irradiance)) return 0;
#endif
  if (clamp_luminance > 0.0f) {
    const float y = lux_luminance(*irradiance);
    if (y > clamp_luminance) {
      const float f = clamp_luminance / y;
      *irradiance *= f;
      *l *= f;
      *nee *= f;
    }
  }
  return 1;
}

inline int lux_path_sample(__global const LuxPath* paths,
                           __global const LuxBasisSample* basis_samples, uint p,
                           float clamp_luminance, float3* irradiance, float3* l, float3* nee) {
  return lux_path_sample_of(paths[p].radiance.xyz, basis_samples, p, clamp_luminance, irradiance, l,
                            nee);
}

#if LUX_RADIANCE_CACHE
/* The texel's feeders (bake/radiance_cache.h): their irradiance without
 * what the cache leaves out (the light-sampled share of the direct light,
 * the last bounce), into the cache's running mean. */
inline void lux_feed_cache(__global const LuxPath* paths,
                           __global const LuxBasisSample* basis_samples, uint first, uint end,
                           float clamp_luminance, __global float4* cache, uint c) {
  for (uint p = first; p < end; ++p) {
    const LuxPath path = paths[p];
    if (path.uncached.w == 0.0f) continue;
    float3 e, l, nee;
    if (lux_path_sample_of(path.radiance.xyz - path.uncached.xyz, basis_samples, p, clamp_luminance,
                           &e, &l, &nee)) {
#if LUX_BASIS
      /* The texel point's light sample, kept apart from `radiance` in basis
       * mode, is left out as in irradiance mode (resolve.h). */
      e -= nee * fmax(basis_samples[p].nee_world.w, 0.0f);
#endif
      lux_cache_add(cache, c, e);
    }
  }
}
#endif

#if LUX_BASIS
#define LUX_BASIS_ADD(p, w)                                                        \
  do {                                                                             \
    const LuxBasisSample bs_ = basis_samples[p];                                   \
    lux_basis_accumulate(basis_state + (size_t)c * params.basis_stride, encodings, \
                         params.encoding_count, basis_dirs, &bs_, l, nee, (w),     \
                         params.acceleration);                                     \
  } while (0)
#else
#define LUX_BASIS_ADD(p, w)
#endif

#if LUX_PROBES
/* DDGI visibility moments of a probe (shared/probe.h): the distance to the
 * first hit along the path's first direction, capped at the probe's maximum
 * distance (probes[].w; a miss counts as that cap), into its direction bin:
 * running means of t and t^2 and the bin's sample count. The bins follow
 * the encodings in the probe's state record. */
inline void lux_probe_visibility(__global float4* bins, float3 dir, float t, float cap) {
  const float d = fmin(t, cap);
  __global float4* b = bins + lux_probe_vis_bin(dir.x, dir.y, dir.z, LUX_PROBE_VIS_SIDE);
  float4 v = *b;
  v.z += 1.0f;
  v.x += (d - v.x) / v.z;
  v.y += (d * d - v.y) / v.z;
  *b = v;
}
#endif

/* c = the covered slot: the index of the texel's state and paths. */
inline void lux_accumulate(uint c, LUX_STAGE_PARAMS(accumulate)) {
  if (c >= params.covered_count) return;
  const uint texel = covered[c];
  uint first = 0, end = 0;
  const int own = lux_offset_range(offsets, c, params.covered_count, &first, &end);
#if !LUX_FILTER_GAUSSIAN
  if (!own) return;
#endif
  /* This texel's running state (the buffers are mean, m2, weight). */
  float4 t_mean = mean[c], t_m2 = m2[c];
  float2 t_weight = weight[c];
  uint dropped = 0;
  const int tx = (int)(texel % params.width), ty = (int)(texel / params.width);
#if LUX_FILTER_GAUSSIAN
  /* Neighbours' paths within the radius, but only from the same instance
   * and a similarly oriented surface: a filter must not carry light across
   * a chart seam into a different surface. */
  const float2 centre = (float2)((float)tx + 0.5f, (float)ty + 0.5f);
  float3 my_normal = (float3)(0.0f);
  int my_instance = -1;
  if (own) {
    const LuxSurfaceTri st = tris[paths[first].pad];
    my_instance = as_int(st.p2.w);
    my_normal = normalize(cross(st.p1.xyz - st.p0.xyz, st.p2.xyz - st.p0.xyz));
  }
  int touched = 0;
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      const int nx = tx + dx, ny = ty + dy;
      if (nx < 0 || ny < 0 || nx >= (int)params.width || ny >= (int)params.height) continue;
      uint nf, ne;
      const uint ns =
          lux_covered_slot(covered, params.covered_count, (uint)(ny * (int)params.width + nx));
      if (!lux_offset_range(offsets, ns, params.covered_count, &nf, &ne)) continue;
      for (uint p = nf; p < ne; ++p) {
        const LuxPath path = paths[p];
        if (dx != 0 || dy != 0) {
          if (my_instance < 0) continue; /* no own path to compare against this time */
          const LuxSurfaceTri st = tris[path.pad];
          if (as_int(st.p2.w) != my_instance) continue;
          const float3 nn = normalize(cross(st.p1.xyz - st.p0.xyz, st.p2.xyz - st.p0.xyz));
          if (dot(nn, my_normal) < 0.9f) continue;
        }
        const float w = lux_filter_weight(path.sample_pos - centre);
        if (!(w > 0.0f)) continue;
        float3 e, l, nee;
        if (!lux_path_sample(paths, basis_samples, p, params.clamp_luminance, &e, &l, &nee)) {
          ++dropped;
          continue;
        }
        lux_welford((float4)(e, lux_luminance(e)), w, &t_mean, &t_m2, &t_weight);
        LUX_BASIS_ADD(p, w);
        touched = 1;
      }
    }
  }
  if (!touched && !own) return;
#else
  for (uint p = first; p < end; ++p) {
#if LUX_PROBES
    lux_probe_visibility(
        basis_state + (size_t)c * params.basis_stride + params.basis_stride - LUX_PROBE_VIS_BINS,
        basis_samples[p].dir_world.xyz, paths[p].sample_pos.x, probes[texel].w);
#endif
    float3 e, l, nee;
    if (!lux_path_sample(paths, basis_samples, p, params.clamp_luminance, &e, &l, &nee)) {
      ++dropped;
      continue;
    }
    lux_welford((float4)(e, lux_luminance(e)), 1.0f, &t_mean, &t_m2, &t_weight);
    LUX_BASIS_ADD(p, 1.0f);
  }
#endif
#if LUX_RADIANCE_CACHE
  if (own)
    lux_feed_cache(paths, basis_samples, first, end, params.clamp_luminance, radiance_cache, c);
#endif
#if LUX_GUIDING
  /* The texel's first-bounce histograms (bake/guiding.h). */
  if (own)
    lux_guide_learn(
        guide + (size_t)c * LUX_GUIDE_STRIDE, paths, first, end,
        lux_shard_sample_index(spp[c] + (end - first), params.shard_index, params.shard_count));
#endif
  mean[c] = t_mean;
  m2[c] = t_m2;
  weight[c] = t_weight;
  spp[c] += own ? end - first : 0u;
  if (dropped) atomic_add(nonfinite, dropped);
}

#endif /* LUXEL_BAKE_ACCUMULATE_H */
