/* The radiance cache (LUX_RADIANCE_CACHE): a final gather from the bake's
 * own lightmap. A lightmap bake estimates the irradiance of every surface
 * at once, so a path leaving texel A that hits a lightmapped diffuse
 * surface at x1 can stop there and take the light x1 reflects from the
 * irradiance that x1's texel has already gathered, instead of tracing on:
 *
 *   L_o(x1, wo) = L_light(x1, wo) + L_rest(x1, wo),
 *   L_rest(x1, wo) ~= A(wo) E_rest(x1) / pi.
 *
 * L_light is a light sample at x1 itself with the full BSDF, MIS-weighted
 * against the texel sensor's (unguided) density instead of the BSDF's
 * (scatter.h, LUX_NEE_AT_PATH_END): the share of each light that light
 * sampling carries best (small and distant lights, their shadow edges and
 * highlights: the sharpest and most directional part of the light at x1)
 * stays exact at the point. E_rest, the cached part, is x1's texel's
 * irradiance without that share: its indirect light and the complementary,
 * BSDF-sampled share of its direct light (large and near lights, where the
 * light sample alone would have unbounded variance, e.g. a wall lit by the
 * wall it meets). The two weights are one partition of unity, the sensor's
 * power heuristic, so nothing is counted twice or lost. The gather is exact
 * for a Lambertian x1 (A = albedo) whose texel's E_rest is E_rest(x1), with
 * that light treated as uniform for the rest of the BSDF (which is why only
 * rough or mostly diffuse vertices gather). A(wo) is estimated by the BSDF
 * sample's own weight, E[f cos / p] = A(wo), so the gather costs one BSDF
 * sample, a texel read and a shadow ray. Device only.
 *
 * What keeps the estimate honest:
 *  - No energy gain through feedback (the failure of bounce-from-the-
 *    lightmap loops that pass over the map repeatedly): the cache is not the
 *    lightmap. It is a running mean per covered texel, fed only by paths
 *    chosen before they start (feeders, chosen by an independent number,
 *    never by what the path finds, so the mean is not biased by the choice),
 *    which trace the whole path and never gather. Feeders leave out the
 *    light-sampled share of their direct light and their last bounce
 *    (LuxPath.uncached, lux_cache_left_out): the cache holds 0 to
 *    max_bounces - 1 bounces, the light sample at x1 adds the rest of x1's
 *    direct light and the gather one bounce to the cached part, so a
 *    gathered path carries exactly the bounces of a traced one.
 *  - Only the first hit gathers, and only on the side the texel records
 *    (the front face: its lightmap normal), at a texel this bake (tile)
 *    holds, with at least one feeder sample, and not within
 *    LUX_CACHE_NEAR_TEXELS texel sizes of the receiver (corners: there the
 *    hit texel's average spans the receiver's own neighbourhood, and the
 *    final-gather bias concentrates; the path is traced on instead).
 *  - Glossy vertices trace on: the cache holds irradiance, not radiance.
 *  - Consistency: a path gathers with probability
 *      P(n) = LUX_CACHE_SHARE min(1, sqrt(LUX_CACHE_FULL_SPP / (n + 1)))
 *    at its texel's sample index n, so the gathered share of a texel's n
 *    samples falls as n^-1/2: the cache's bias (the texel average against
 *    the point, the uniform-light assumption) falls with the Monte Carlo
 *    error, and the estimate converges to the path-traced one. The cached
 *    means themselves are unbiased: any cache value gives an unbiased
 *    gather of the texel-averaged irradiance, so few feeder samples make a
 *    noisy cache, not a dark one.
 *  - Determinism: the role is a hash of the texel's seed and sample index,
 *    and shade reads the cache as the previous iterations left it
 *    (accumulate updates it after shade), so the same seed gives the same
 *    bits for any thread count. A resumed bake starts with an empty cache
 *    (the cache is not part of the checkpoint): its result is as valid, and
 *    differs in its bits from an uninterrupted bake's. */
#ifndef LUXEL_BAKE_RADIANCE_CACHE_H
#define LUXEL_BAKE_RADIANCE_CACHE_H

#include "bake/path.h"
#include "bake/scatter.h"
#include "shading/bsdf.h"
#include "shared/bake.h"
#include "shared/geometry.h"

#if LUX_RADIANCE_CACHE && LUX_PROBES
#error "the radiance cache is for lightmaps: probes have no texels to gather from"
#endif

/* Most of a texel's early paths gather; a quarter always feed the cache. */
#define LUX_CACHE_SHARE 0.75f
/* Sample index up to which the share stays LUX_CACHE_SHARE. */
#define LUX_CACHE_FULL_SPP 64.0f
/* Hits nearer than this many texel sizes (of the hit's texels) trace on. */
#define LUX_CACHE_NEAR_TEXELS 8.0f
/* A vertex gathers when its GGX layer takes at most this share of the
 * sampling (a mostly diffuse dielectric) or its roughness is at least
 * LUX_CACHE_MIN_ROUGHNESS (a lobe broad enough for the uniform-light
 * assumption). */
#define LUX_CACHE_MAX_SPECULAR_SHARE 0.1f
#define LUX_CACHE_MIN_ROUGHNESS 0.5f
/* The dimension of the role's independent number (lux_independent_1d),
 * apart from the sequence's vertex dimensions. */
#define LUX_DIM_CACHE_ROLE 0x0CAC4Eu

/* The weight of an emissive triangle's light that a path found (along
 * `dir`, after `depth` bounces, with MIS weight w; light_pdf: the light
 * sampler's density of that direction, 0 where a light sample cannot reach
 * it; dir unit) that the cache leaves out:
 *  - the last bounce, all of it: a gather adds one bounce;
 *  - what the texel's first segment finds, all but its BSDF-sampling
 *    share: the gather's light sample of an emissive triangle is weighted
 *    against the sensor's unguided density (scatter.h,
 *    LUX_NEE_AT_PATH_END), so the cache keeps the complement,
 *    power(p_sensor, p_light), whatever density (guided or not) drew the
 *    direction and whatever MIS weight the texel itself gave it (analytic
 *    lights: 0). The texel point's own light sample is left out whole
 *    (raygen.h, resolve.h).
 *  - nothing else. */
inline float lux_cache_left_out(uint depth, uint max_bounces, float w, float light_pdf, float3 dir,
                                float3 sensor_normal) {
  if (depth == max_bounces) return w;
  if (depth != 0u) return 0.0f;
  const float cos_s = dot(dir, sensor_normal);
  const float kept =
      light_pdf > 0.0f ? lux_power_heuristic(LUX_SENSOR_PDF(fmax(cos_s, 0.0f)), light_pdf) : 1.0f;
  return w - kept;
}

/* The same for the sky: its direct light is left out whole, since the
 * gather's light sample takes all of it (weight 1: no distance, so no
 * corner where light sampling alone fails), exact at the hit point; a
 * share cached from texel averages carried the windows' light patterns
 * into gathers (docs/accuracy.md "Radiance cache"). */
inline float lux_cache_sky_left_out(uint depth, uint max_bounces, float w) {
  return depth == 0u || depth == max_bounces ? w : 0.0f;
}

/* Whether the path with sample index `index` of its texel feeds the cache
 * (traces everything, never gathers). */
inline int lux_cache_feeds(uint index, uint seed) {
  const float n = (float)index + 1.0f;
  const float share = LUX_CACHE_SHARE * fmin(1.0f, sqrt(LUX_CACHE_FULL_SPP / n));
  return lux_independent_1d(index, LUX_DIM_CACHE_ROLE, seed) >= share;
}

inline int lux_cache_gathers_at(const LuxBsdf* bsdf) {
#if LUX_SPECULAR
  return bsdf->p_specular <= LUX_CACHE_MAX_SPECULAR_SHARE ||
         bsdf->roughness >= LUX_CACHE_MIN_ROUGHNESS;
#else
  (void)bsdf;
  return 1;
#endif
}

/* The cached irradiance at a hit (barycentrics u, v on triangle `tri`,
 * distance t from the previous vertex): 1 and *e when the hit's texel holds
 * a usable mean. */
inline int lux_cache_lookup(LuxBakeParams params, __global const LuxSurfaceTri* tris,
                            __global const LuxTriangleUV* atlas_uvs, __global const uint* covered,
                            __global const float4* cache, int tri, float u, float v, float t,
                            float3* e) {
  const LuxTriangleUV a = atlas_uvs[tri];
  const float w = (float)params.width, h = (float)params.height;
  const float2 e1 = (a.uv1 - a.uv0) * (float2)(w, h), e2 = (a.uv2 - a.uv0) * (float2)(w, h);
  const float texel_area = fabs(e1.x * e2.y - e1.y * e2.x); /* twice, in texels^2 */
  if (!(texel_area > 0.0f)) return 0;                       /* no lightmap on this triangle */
  const LuxSurfaceTri st = tris[tri];
  const float world_area = length(cross(st.p1.xyz - st.p0.xyz, st.p2.xyz - st.p0.xyz));
  /* One texel's side in world units at the hit, from the two areas. */
  const float texel_size = sqrt(world_area / texel_area);
  if (!(t >= LUX_CACHE_NEAR_TEXELS * texel_size)) return 0;
  const float2 uv = a.uv0 + u * (a.uv1 - a.uv0) + v * (a.uv2 - a.uv0);
  const int x = clamp((int)floor(uv.x * w), 0, (int)params.width - 1);
  const int y = clamp((int)floor(uv.y * h), 0, (int)params.height - 1);
  const uint slot =
      lux_covered_slot(covered, params.covered_count, (uint)y * params.width + (uint)x);
  if (slot == LUX_NO_SLOT) return 0;
  const float4 c = cache[slot];
  if (!(c.w >= 1.0f)) return 0;
  *e = c.xyz;
  return 1;
}

/* Adds one feeder's sample (its irradiance without what
 * lux_cache_left_out leaves out) to its texel's running mean: xyz = mean,
 * w = samples. */
inline void lux_cache_add(__global float4* cache, uint slot, float3 e) {
  float4 c = cache[slot];
  c.w += 1.0f;
  /* radiance - uncached can round a hair below 0. */
  c.xyz += (fmax(e, (float3)(0.0f)) - c.xyz) / c.w;
  cache[slot] = c;
}

#endif /* LUXEL_BAKE_RADIANCE_CACHE_H */
