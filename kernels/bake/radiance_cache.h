/* The radiance cache (LUX_RADIANCE_CACHE): a final gather from the bake's
 * own lightmap. A lightmap bake estimates the irradiance of every surface
 * at once, so a path leaving texel A that hits a lightmapped diffuse
 * surface at x1 can stop there and take the light x1 reflects from the
 * irradiance that x1's texel has already gathered, instead of tracing on:
 *
 *   L_o(x1, wo) ~= A(wo) E(x1) / pi,
 *
 * exact for a Lambertian x1 (A = albedo) whose texel's irradiance is E(x1),
 * and the light arriving at x1 treated as uniform for the rest of the BSDF
 * (which is why only rough or mostly diffuse vertices gather). A(wo) is
 * estimated by the BSDF sample's own weight, E[f cos / p] = A(wo), so the
 * gather costs one BSDF sample and a texel read. Device only.
 *
 * What keeps the estimate honest:
 *  - No energy gain through feedback (the failure of bounce-from-the-
 *    lightmap loops that pass over the map repeatedly): the cache is not the
 *    lightmap. It is a running mean per covered texel, fed only by paths
 *    chosen before they start (feeders, chosen by an independent number,
 *    never by what the path finds, so the mean is not biased by the choice),
 *    which trace the whole path and never gather. Feeders leave out their
 *    last bounce (LuxPath.last_bounce): the cache holds E with at most
 *    max_bounces - 1 bounces, and a gather at the first hit adds one, so a
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

/* Adds one feeder's sample (irradiance with at most max_bounces - 1
 * bounces) to its texel's running mean: xyz = mean, w = samples. */
inline void lux_cache_add(__global float4* cache, uint slot, float3 e) {
  float4 c = cache[slot];
  c.w += 1.0f;
  /* radiance - last_bounce can round a hair below 0. */
  c.xyz += (fmax(e, (float3)(0.0f)) - c.xyz) / c.w;
  cache[slot] = c;
}

#endif /* LUXEL_BAKE_RADIANCE_CACHE_H */
