/* Stage 2, primary rays from texels (thesis §3.4, Listing 4.2): one path
 * per slot of the sorted texel keys, starting at a valid sample position of
 * its texel, with next-event estimation at the texel point and the first
 * segment about the shading normal. Device only. */
#ifndef LUXEL_BAKE_RAYGEN_H
#define LUXEL_BAKE_RAYGEN_H

#include "bake/guiding.h"
#include "bake/path.h"
#include "bake/radiance_cache.h"
#include "bake/scatter.h"
#include "bake/surface.h"
#include "primitives/offset_buffer.h"
#include "shared/bake_args.h"
#include "shared/probe.h"
#include "shared/sample_info.h"
#include "shared/shard.h"
#if LUX_BASIS
#include "bake/basis.h"
#endif

inline void lux_raygen(uint gid, LUX_STAGE_PARAMS(raygen)) {
  if (gid >= (uint)*count) return;
  const uint slot = keys[gid]; /* covered slot: index of the per-texel state */
  const uint texel = covered[slot];
  /* Rank of this path among the texel's paths of this iteration: the
   * texel's sample index continues its progressive sequence (§6.2) without
   * atomics, so results do not depend on scheduling. */
  uint first = 0, end = 0;
  lux_offset_range(offsets, slot, params.covered_count, &first, &end);
  /* A shard's own count maps to its part of the sequence (shared/shard.h). */
  const uint index =
      lux_shard_sample_index(spp[slot] + (gid - first), params.shard_index, params.shard_count);
#if LUX_GUIDING
  /* Guiding: each epoch of the texel's samples its own scramble
   * (bake/guiding.h). */
  const uint seed = lux_guide_seed(lux_texel_seed(texel, params.bake_seed), index);
#else
  const uint seed = lux_texel_seed(texel, params.bake_seed);
#endif

#if LUX_PROBES
  /* Probe domain: the "texel" is a probe, a point in free space whose
   * domain is the whole sphere. Each path draws a random sensor normal n,
   * uniform over the sphere, and is then exactly the texel estimator of the
   * directional encodings about n: first segment uniform over n's
   * hemisphere, NEE with MIS against it. That path estimates the moments
   * over H(n); since every direction lies in H(n) with probability 1/2, twice
   * it is an unbiased estimate over the sphere (basis.h, accumulate.h), and
   * the first directions are uniform over the sphere. Keeping the texel
   * sensor keeps every MIS weight of scatter.h and shade.h consistent. */
  const float4 probe = probes[texel];
  const float3 probe_n =
      lux_uniform_sphere(lux_sample_2d(index, LUX_DIM_TEXEL_SAMPLE, seed ^ 0x68bc21ebu));
  const int tri = 0;
  const uint tx = texel, ty = 0;
  const float2 offset = (float2)(0.5f, 0.5f);
  LuxSurface s;
  s.p = probe.xyz;
  s.ng = probe_n;
  s.ng_front = probe_n;
  s.ns = probe_n;
  s.uv = (float2)(0.0f, 0.0f);
  s.uv1 = s.uv;
  s.material = 0;
  s.light = -1;
#else
  /* Listing 4.2: choose one of the texel's valid Hammersley positions. */
  const uint word_offset = sample_offsets[slot];
  const uint valid = popcount(sample_words[word_offset]) + popcount(sample_words[word_offset + 1]);
  const float u_sample = lux_sample_1d(index, LUX_DIM_TEXEL_SAMPLE, seed);
  const uint rank = min((uint)(u_sample * (float)valid), valid - 1u);
  uint instance, mesh_tri, hammersley;
  lux_sample_info_lookup(sample_words, word_offset, rank, &instance, &mesh_tri, &hammersley);
  const int tri = (int)(instance_first[instance] + mesh_tri);
  const uint tx = texel % params.width, ty = texel / params.width;
  const float2 offset = lux_hammersley64(hammersley);
  const LuxTriangleUV uvt = atlas_uvs[tri];
  /* Barycentrics in the lightmap, in the sample point's frame so the
   * arithmetic stays in small magnitudes (§3.4: "high-precision
   * calculations ... to avoid invalid values"; kernels/shared/sample_info.h). */
  float w0, w1, w2;
  lux_texel_barycentrics((float2)(uvt.uv0.x, uvt.uv0.y), (float2)(uvt.uv1.x, uvt.uv1.y),
                         (float2)(uvt.uv2.x, uvt.uv2.y), (float)params.width, (float)params.height,
                         tx, ty, offset, &w0, &w1, &w2);
  const float2 bary = (float2)(w1, w2);
  LuxSurface s = lux_surface_at(tris, tri, bary.x, bary.y);
#endif
#if LUX_NORMAL_MAP && !LUX_BASIS
  /* Irradiance lightmaps integrate about the normal-mapped normal, what the
   * surface's shading sees; directional encodings record the light arriving
   * at the unmapped surface, and the runtime applies the normal map when it
   * reconstructs (docs/accuracy.md "Normal maps"). */
  {
#if LUX_TEXCOORD1
    s.uv1 = lux_surface_uv1(material_uv1, tri, bary.x, bary.y);
#endif
    const LuxMaterial m = materials[s.material];
    lux_surface_normal_map(&s, &m, textures, texels, tangents, tri, bary.x, bary.y);
  }
#endif

  LuxPath path;
  path.texel = texel;
  path.sample_index = index;
  path.seed = seed;
  path.depth = 0;
  path.sample_pos = (float2)((float)tx + offset.x, (float)ty + offset.y);
#if LUX_PROBES
  /* The first hit's distance, set by shade; a path that never gets there
   * counts as a miss. */
  path.sample_pos.x = INFINITY;
#endif
  path.pad = (uint)tri;
  path.radiance = (float4)(0.0f);
  path.uncached = (float4)(0.0f);
#if LUX_RADIANCE_CACHE
  path.uncached.w = lux_cache_feeds(index, seed) ? 1.0f : 0.0f;
#endif
  path.prev_pos = (float4)(s.p, 0.0f);
  path.prev_normal = (float4)(s.ns, 0.0f);

  float3 t, b;
  lux_onb(s.ns, &t, &b);
  const uint dim = LUX_DIM_VERTEX(0);
#if LUX_GUIDING
  /* This texel's learned first-bounce histogram (bake/guiding.h). */
  __global const float4* guide_h = guide + (size_t)slot * LUX_GUIDE_STRIDE;
  const float guide_total =
      lux_guide_epoch(index) >= LUX_GUIDE_FIRST_GUIDED_EPOCH ? lux_guide_total(guide_h) : 0.0f;
#else
  __global const float4* guide_h = 0;
  const float guide_total = 0.0f;
#endif
  LuxRay shadow;
  float3 contribution;
  LuxBsdf unused_bsdf;
  int analytic_sample;
  float3 analytic_e;
  lux_next_event(params LUX_GROUP_ARGS(scene) LUX_GROUP_ARGS(textures) LUX_GROUP_ARGS(lights), &s,
                 LUX_NEE_AT_SENSOR, &unused_bsdf, t, b, s.ns, (float3)(0.0f, 0.0f, 1.0f),
                 (float3)(1.0f), index, dim, seed, guide_h, guide_total, &shadow, &contribution,
                 &analytic_sample, &analytic_e);
#if LUX_DIRECT_ANALYTIC
#if LUX_BASIS
#error "LUX_DIRECT_ANALYTIC is for irradiance lightmaps only"
#endif
  /* Analytic direct light (support thesis Eq. 2.25, Heitz et al. 2018).
   * Eq. 2.25 writes the shadowed irradiance as E_u (exact, unshadowed;
   * shading/analytic_light.h) times the ratio sum(f V / p) / sum(f / p) of
   * light samples. lux_next_event picks the analytic light in proportion to
   * its exact irradiance here (luminance), so every analytic sample has
   * f / p = E_u / P_a (P_a: the analytic lights' share of the light table),
   * and the one-sample ratio E_u (f V / p) / (f / p), over the choice of the
   * analytic part, is the plain term f V / p: unbiased at every sample
   * count and never negative. Where P_a = 1 (no sky, sun disc or textured
   * emitter besides the analytic lights) and the lights share a colour, it
   * is exact wherever the texel point sees all or none of them. Nothing is
   * added here: resolve_shadows adds f V / p as for any light sample.
   *
   * The difference form E_u - (f / p)(1 - V) used before is unbiased too,
   * but one occluded sample gives E_u (1 - 1 / P_a) < 0 when P_a < 1, and a
   * negative channel for a light whose colour differs from the others' (the
   * choice follows luminance, not each channel): delivered lightmaps had
   * negative texels. The ratio proper over per-texel sums is non-negative
   * but biased at low counts and needs per-texel state in checkpoints, tiles
   * and shard merges (docs/accuracy.md, "Analytic direct light"). */
  (void)analytic_sample;
  (void)analytic_e;
#endif
  shadow_rays[gid] = shadow;
#if LUX_RADIANCE_CACHE
  /* w = 1: the texel point's light sample, which the radiance cache leaves
   * out (resolve.h, bake/radiance_cache.h). */
  shadow_contrib[gid] = (float4)(contribution, 1.0f);
#else
  shadow_contrib[gid] = (float4)(contribution, 0.0f);
#endif

  /* First segment about the shading normal: cosine-weighted (weight pi) for
   * irradiance, uniform (weight 1, radiance) for directional encodings. A
   * direction under the geometric surface (smoothed normals) carries nothing. */
  const float2 u_dir = lux_sample_2d(index, dim + LUX_DIM_DIRECTION, seed);
#if LUX_BASIS
  /* The texel's tangent frame, reproducible by an engine: x follows the
   * lightmap's +u on the surface, z the shading normal. Probes have no
   * surface: their encodings are in the world frame only. */
#if LUX_PROBES
  const float3 tn = t;
#else
  const float3 tn = lux_lightmap_tangent(tris[tri], uvt, s.ns, t);
#endif
  t = tn;
  b = cross(s.ns, tn);
  const float3 dir_local = lux_uniform_hemisphere(u_dir);
#elif LUX_GUIDING
  /* The one-sample mixture of the learned histogram and the cosine lobe;
   * weight cos / p = pi / m (bake/guiding.h). The layer dimension of the
   * texel point is otherwise unused. */
  const float u_strategy = lux_sample_1d(index, dim + LUX_DIM_LAYER, seed);
  const float3 dir_local = lux_guide_sample(guide_h, guide_total, u_strategy, u_dir);
#else
  const float3 dir_local = lux_cosine_hemisphere(u_dir);
#endif
  const float3 wi = lux_to_world(dir_local, t, b, s.ns);
  const int ok = dot(wi, s.ng) > 0.0f;
#if LUX_GUIDING
  const float guide_m = lux_guide_factor(guide_h, guide_total, dir_local);
  path.throughput =
      (float4)((float3)(LUX_SENSOR_WEIGHT / guide_m), LUX_SENSOR_PDF(dir_local.z) * guide_m);
  /* A direction under the surface carries nothing and teaches nothing. */
  path.prev_pos.w = ok ? (float)lux_guide_bin(dir_local) : -1.0f;
#else
  path.throughput = (float4)(LUX_SENSOR_WEIGHT, LUX_SENSOR_WEIGHT, LUX_SENSOR_WEIGHT,
                             LUX_SENSOR_PDF(dir_local.z));
#endif
#if LUX_BASIS
  {
    LuxBasisSample bs;
    bs.dir_world = (float4)(wi, dir_local.z);
    bs.dir_tangent = (float4)(dir_local, dir_local.z);
    /* The light sample as radiance over density: the irradiance contribution
     * without its cosine. Visibility (nee.w) comes from resolve_texel_shadows. */
    const float3 ld = shadow.dir_tmax.xyz;
    const float len = length(ld);
    const float3 lw = len > 0.0f ? ld / len : (float3)(0.0f, 0.0f, 1.0f);
    const float3 ll = lux_to_local(lw, t, b, s.ns);
    const float cos_l = dot(lw, s.ns);
    bs.nee_world = (float4)(lw, cos_l);
    bs.nee_tangent = (float4)(ll, cos_l);
    bs.nee = cos_l > 0.0f && len > 0.0f ? (float4)(contribution / cos_l, 0.0f) : (float4)(0.0f);
    basis_samples[gid] = bs;
  }
#endif
  path.alive = ok ? 1u : 0u;
  paths[gid] = path;
  rays[gid] = ok ? lux_make_ray(lux_offset_origin(s.p, s.ng, wi, params.offset_scale), wi, INFINITY)
                 : lux_no_ray();
  active[gid] = lux_tag_slot(gid, wi);
}

#endif /* LUXEL_BAKE_RAYGEN_H */
