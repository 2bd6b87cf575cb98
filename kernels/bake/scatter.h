/* Scattering at a path vertex: next-event estimation (thesis §6.1) and the
 * extension ray (BSDF importance sampling, §6.3.1, Eq. 6.2), with multiple
 * importance sampling (power heuristic) between the two strategies for lights
 * a BSDF ray can also hit (emissive triangles, the sky).
 *
 * Vertex 0 is the texel's surface point, a "sensor" rather than a material:
 * irradiance E = integral of L cos over the hemisphere, i.e. a BSDF f = 1
 * sampled with the cosine pdf cos/pi (§3.4: "the PDF ... cancels with the
 * Lambertian BRDF"; here the extension weight is cos / (cos/pi) = pi).
 *
 * Sample dimensions (§6.2, one progressive sequence per dimension): 0 picks
 * the texel's sample position; vertex k uses LUX_DIM_VERTEX(k) + 0..4. */
#ifndef LUXEL_BAKE_SCATTER_H
#define LUXEL_BAKE_SCATTER_H

#include "bake/guiding.h"
#include "bake/path.h"
#include "bake/surface.h"
#include "shading/analytic_light.h"
#include "shading/bsdf.h"
#include "shading/lights.h"
#include "shading/texture.h"
#include "shared/bake_args.h"

#define LUX_DIM_TEXEL_SAMPLE 0u
#define LUX_DIM_VERTEX(k) (1u + 5u * (k))
#define LUX_DIM_LIGHT_SELECT 0u
#define LUX_DIM_LIGHT_POINT 1u
#define LUX_DIM_LAYER 2u
#define LUX_DIM_DIRECTION 3u
#define LUX_DIM_ROULETTE 4u

inline float lux_power_heuristic(float a, float b) {
  const float a2 = a * a, b2 = b * b;
  return a2 + b2 > 0.0f ? a2 / (a2 + b2) : 0.0f;
}

inline float lux_max3(float3 v) {
  return fmax(v.x, fmax(v.y, v.z));
}

inline int lux_finite3(float3 v) {
  return isfinite(v.x) && isfinite(v.y) && isfinite(v.z);
}

/* A shadow ray that intersect_any_indexed skips (empty interval). */
inline LuxRay lux_no_ray(void) {
  LuxRay r;
  r.org_tmin = (float4)(0.0f, 0.0f, 0.0f, 1.0f);
  r.dir_tmax = (float4)(0.0f, 0.0f, 1.0f, -1.0f);
  return r;
}

inline LuxRay lux_make_ray(float3 org, float3 dir, float tmax) {
  LuxRay r;
  r.org_tmin = (float4)(org, 0.0f);
  r.dir_tmax = (float4)(dir, tmax);
  return r;
}

/* Where next-event estimation happens (lux_next_event's `at`):
 *  - LUX_NEE_AT_VERTEX: a path vertex whose BSDF-sampled extension follows,
 *    so light samples are MIS-weighted against the BSDF's density (§5.1);
 *  - LUX_NEE_AT_SENSOR: the texel point (f = 1, cosine pdf, times the
 *    first-bounce guide's factor when `guide` is not null: bake/guiding.h);
 *  - LUX_NEE_AT_PATH_END: the radiance cache's gather (bake/radiance_cache.h),
 *    where the path ends: no BSDF-sampled hit follows. The share of an
 *    emissive triangle's light that BSDF sampling would carry comes from
 *    the cache, which holds it as the texel sensor's first segments found
 *    it, so the light sample of a triangle is weighted against the sensor's
 *    density (unguided), the complement of the cached share, whatever the
 *    BSDF here; the sky's light is all the light sample's (weight 1). */
#define LUX_NEE_AT_VERTEX 0
#define LUX_NEE_AT_SENSOR 1
#define LUX_NEE_AT_PATH_END 2

/* Next-event estimation from surface s, at the sensor or at a vertex with
 * the material's BSDF in the local frame (t, b, n), wo local. Writes the
 * shadow ray and its unoccluded contribution (throughput applied). */
inline void lux_next_event(LuxBakeParams params LUX_GROUP_PARAMS(in, scene)
                               LUX_GROUP_PARAMS(in, textures) LUX_GROUP_PARAMS(in, lights),
                           const LuxSurface* s, int at, const LuxBsdf* bsdf, float3 t, float3 b,
                           float3 n, float3 wo_local, float3 throughput, uint index, uint dim,
                           uint seed, __global const float4* guide, float guide_total,
                           LuxRay* shadow_ray, float3* contribution, int* analytic_sample,
                           float3* analytic_e) {
  *shadow_ray = lux_no_ray();
  *contribution = (float3)(0.0f);
  *analytic_sample = 0;
  *analytic_e = (float3)(0.0f);
#if LUX_NEE
  const int sensor = at == LUX_NEE_AT_SENSOR;
  if (params.light_count == 0u) return;
  const float u_sel = lux_sample_1d(index, dim + LUX_DIM_LIGHT_SELECT, seed);
  const float2 u_pt = lux_sample_2d(index, dim + LUX_DIM_LIGHT_POINT, seed);
  float select = 0.0f;
  uint light = lux_sample_alias(light_select, params.light_count, u_sel, &select);
#if LUX_DIRECT_ANALYTIC
  if (sensor) {
    /* At the texel point (raygen.h) the analytic lights' exact irradiance is
     * E_a = sum of e_k. When the power table picks an analytic light
     * (probability P_a, their total pmf), the light actually sampled is
     * analytic light k with probability e_k / e_a (luminance of each one's
     * exact irradiance here), so the sample's f / p is E_a / P_a (in
     * luminance) whatever the lights' sizes and distances, and f V / p is
     * the one-sample ratio estimate of Eq. 2.25 (support thesis), exact in
     * umbra and full light alike when P_a = 1. Lights that are not analytic
     * keep their power pmf, so MIS with first segments stays consistent;
     * analytic ones get no MIS, and first segments ignore them (shade.h).
     * E_a is returned for the caller's information only. */
    const LuxLight picked = lights[light];
    float p_a = 0.0f, w_sum = 0.0f, w_chosen = 0.0f;
    int chosen = -1;
    for (uint i = 0; i < params.light_count; ++i) {
      const LuxLight l = lights[i];
      if (!lux_light_is_analytic(&l)) continue;
      p_a += light_select[i].pmf;
      const float3 e = lux_light_irradiance(&l, s->p, n, s->ng);
      const float w = lux_luminance(e);
      if (!(w > 0.0f)) continue;
      *analytic_e += e;
      w_sum += w;
      /* Weighted reservoir sampling (one independent number per candidate):
       * light i is kept with probability w_i / sum of all w. The first
       * candidate is always kept (u w < w for u < 1, so this changes nothing
       * for finite weights); an overflowing irradiance (w = inf, where
       * u * inf < inf fails) then still gives a sample, whose non-finite
       * value the accumulation counts and drops instead of losing the light. */
      if (chosen < 0 || lux_independent_1d(index, 0x40000000u + i, seed) * w_sum < w) {
        chosen = (int)i;
        w_chosen = w;
      }
    }
    if (lux_light_is_analytic(&picked)) {
      *analytic_sample = 1;
      if (chosen < 0) return; /* no analytic light reaches p: nothing to shadow */
      light = (uint)chosen;
      /* inf / inf when the irradiance overflowed: keep the pdf finite so
       * the sample's own non-finite value reaches the accumulation. */
      const float share = w_chosen / w_sum;
      select = p_a * (isfinite(share) ? share : 1.0f);
    }
  }
#endif
  LuxLightSample ls;
  if (!lux_sample_light_at(lights, light, select, sky, sky_texels, sky_block_cdfs, sky_texel_cdfs,
                           s->p, n, u_pt, &ls))
    return;
  if (!(ls.pdf > 0.0f) || dot(ls.wi, s->ng) <= 0.0f) return;
  float3 radiance = ls.radiance;
#if LUX_EMISSIVE_TEXTURE
  if (ls.triangle >= 0) {
    LuxSurface e = lux_surface_at(tris, ls.triangle, ls.bary.x, ls.bary.y);
#if LUX_TEXCOORD1
    e.uv1 = lux_surface_uv1(material_uv1, ls.triangle, ls.bary.x, ls.bary.y);
#endif
    const LuxMaterial em = materials[e.material];
    if (em.emissive_tex.texture >= 0)
      radiance *= lux_texture_slot_sample(texels, textures, em.emissive_tex, e.uv, e.uv1).xyz;
  }
#endif
  const float3 wi_local = lux_to_local(ls.wi, t, b, n);
  const float cos_i = wi_local.z;
  if (cos_i <= 0.0f) return;
  /* MIS only for lights a BSDF ray can also reach (emissive triangles, the
   * sky); the sun disc and punctual lights are NEE-only with weight 1. */
  const int mis = !ls.is_delta && ls.mis && !*analytic_sample;
  float3 f_weighted;
  if (at == LUX_NEE_AT_PATH_END) {
    /* Emissive triangles share with the cache; the sky it leaves out whole
     * (bake/radiance_cache.h). */
    const float w =
        mis && isfinite(ls.dist) ? lux_power_heuristic(ls.pdf, LUX_SENSOR_PDF(cos_i)) : 1.0f;
    f_weighted = (float3)(0.0f);
    for (int layer = 0; layer < 2; ++layer)
      f_weighted += lux_bsdf_eval_layer(bsdf, layer, wo_local, wi_local) * w;
  } else if (sensor) {
    float p_sensor = LUX_SENSOR_PDF(cos_i);
#if LUX_GUIDING
    if (guide) p_sensor *= lux_guide_factor(guide, guide_total, wi_local);
#else
    (void)guide;
    (void)guide_total;
#endif
    const float w = mis ? lux_power_heuristic(ls.pdf, p_sensor) : 1.0f;
    f_weighted = (float3)(w);
  } else {
    f_weighted = (float3)(0.0f);
    for (int layer = 0; layer < 2; ++layer) {
      const float3 f = lux_bsdf_eval_layer(bsdf, layer, wo_local, wi_local);
      if (lux_max3(f) <= 0.0f) continue;
      const float w =
          mis ? lux_power_heuristic(ls.pdf, lux_bsdf_pdf_layer(bsdf, layer, wo_local, wi_local))
              : 1.0f;
      f_weighted += f * w;
    }
  }
  *contribution = throughput * f_weighted * radiance * (cos_i / ls.pdf);
  const float3 org = lux_offset_origin(s->p, s->ng, ls.wi, params.offset_scale);
  if (!isfinite(ls.dist)) {
    *shadow_ray = lux_make_ray(org, ls.wi, INFINITY);
    return;
  }
  /* Finite lights: aim at the light point pulled back off its own surface by
   * the same robust offset (kernels/shared/ray_offset.h), so the shadow ray
   * neither reaches the emitter itself nor depends on the scene's scale (a
   * relative tmax margin fails at 1e-3 units, where the origin offset is
   * larger than the margin). Direction unnormalised, tmax = 1. */
  const float3 q = lux_offset_origin(s->p + ls.wi * ls.dist, -ls.wi, -ls.wi, params.offset_scale);
  const float3 d = q - org;
  /* Receiver and light point closer than the offsets (touching surfaces):
   * nothing can lie between them. */
  *shadow_ray = dot(d, ls.wi) > 0.0f ? lux_make_ray(org, d, 1.0f) : lux_no_ray();
#endif
}

#endif /* LUXEL_BAKE_SCATTER_H */
