/* Stage 3, shading of closest hits (thesis §5.1 steps 3b/3d): one
 * work-item per live path of the active list. Adds emission (MIS-weighted
 * against the NEE that the previous vertex did), then at vertices within the
 * bounce limit: NEE, BSDF sampling of the extension ray (Eq. 6.2), Russian
 * roulette. Writes alive[j] (and tagged[j]) for compaction. Device only. */
#ifndef LUXEL_BAKE_SHADE_H
#define LUXEL_BAKE_SHADE_H

#include "bake/path.h"
#include "bake/radiance_cache.h"
#include "bake/scatter.h"
#include "bake/surface.h"
#include "shared/bake_args.h"

inline void lux_shade(uint j, LUX_STAGE_PARAMS(shade)) {
  if (j >= (uint)*count) return;
  const uint slot = active[j] & LUX_SLOT_MASK;
  LuxPath path = paths[slot];
  alive[j] = 0u;
  tagged[j] = slot;
  shadow_rays[slot] = lux_no_ray();
  shadow_contrib[slot] = (float4)(0.0f);
  if (!path.alive) return;

#if LUX_GUIDING
  /* All `radiance` holds before the first hit is the texel point's light
   * sample, which the guide leaves out (bake/guiding.h). */
  if (path.depth == 0u) path.prev_normal.w = lux_luminance(path.radiance.xyz);
#endif
  const LuxRay ray = rays[slot];
  const LuxHit hit = hits[slot];
  const float3 dir = ray.dir_tmax.xyz;
  float3 throughput = path.throughput.xyz;
  const float prev_pdf = path.throughput.w;
#if LUX_PROBES
  /* The probe's first segment: its distance to the first hit (infinite on a
   * miss) for the visibility moments (shared/probe.h); the probe domain has
   * no texel-space sample position to keep there. */
  if (path.depth == 0u) path.sample_pos.x = hit.prim < 0 ? INFINITY : hit.t;
#endif

  if (hit.prim < 0) {
#if LUX_SKY || LUX_SKY_IMAGE
    const float3 l = lux_sky_radiance(sky, sky_texels, dir);
    float w = 1.0f;
    if (prev_pdf > 0.0f && params.sky_light >= 0)
      w = lux_power_heuristic(
          prev_pdf, lux_sky_pdf(sky, light_select, params.sky_light, sky_block_cdfs, sky_texel_cdfs,
                                dir, path.prev_normal.xyz));
    path.radiance.xyz += throughput * l * w;
#if LUX_RADIANCE_CACHE
    path.uncached.xyz += throughput * l * lux_cache_sky_left_out(path.depth, params.max_bounces, w);
#endif
#endif
    path.alive = 0u;
    paths[slot] = path;
    rays[slot] = lux_no_ray();
    return;
  }

  LuxSurface s = lux_surface_at(tris, hit.prim, hit.u, hit.v);
#if LUX_TEXCOORD1
  s.uv1 = lux_surface_uv1(material_uv1, hit.prim, hit.u, hit.v);
#endif
  const LuxMaterial m = materials[s.material];
  const float3 wo = -normalize(dir);

#if LUX_LIGHT_EMISSIVE
  if ((m.flags & LUX_MATERIAL_EMISSIVE) &&
      (dot(wo, s.ng_front) > 0.0f || (m.flags & LUX_MATERIAL_DOUBLE_SIDED))) {
    float3 le = m.emission.xyz;
#if LUX_EMISSIVE_TEXTURE
    if (m.emissive_tex.texture >= 0)
      le *= lux_texture_slot_sample(texels, textures, m.emissive_tex, s.uv, s.uv1).xyz;
#endif
    float w = 1.0f, light_pdf = 0.0f;
    if (prev_pdf > 0.0f && s.light >= 0) {
      light_pdf =
          lux_light_pdf_triangle(lights, light_select, s.light, path.prev_pos.xyz, s.p, s.ng_front);
      w = lux_power_heuristic(prev_pdf, light_pdf);
    }
#if LUX_DIRECT_ANALYTIC
    /* The texel point's light sample carries this emitter alone, with MIS
     * weight 1 (scatter.h, raygen.h): its first segment must not count it
     * again. */
    if (path.depth == 0u && s.light >= 0) {
      const LuxLight hit_light = lights[s.light];
      if (lux_light_is_analytic(&hit_light)) w = 0.0f;
    }
#endif
    path.radiance.xyz += throughput * le * w;
#if LUX_RADIANCE_CACHE
    path.uncached.xyz +=
        throughput * le *
        lux_cache_left_out(path.depth, params.max_bounces, w, light_pdf, -wo, path.prev_normal.xyz);
#endif
  }
#endif

  path.depth += 1u;
  if (path.depth > params.max_bounces) {
    path.alive = 0u;
    paths[slot] = path;
    rays[slot] = lux_no_ray();
    return;
  }

  /* Material at the hit. Shading frame on the side the ray arrives from. */
  float3 base = m.base_color.xyz;
  float metallic = m.metallic, roughness = m.roughness;
#if LUX_TEXTURES
  if (m.base_color_tex.texture >= 0)
    base *= lux_texture_slot_sample(texels, textures, m.base_color_tex, s.uv, s.uv1).xyz;
  if (m.metallic_roughness_tex.texture >= 0) {
    const float4 mr =
        lux_texture_slot_sample(texels, textures, m.metallic_roughness_tex, s.uv, s.uv1);
    roughness *= mr.y;
    metallic *= mr.z;
  }
#endif
#if LUX_NORMAL_MAP
  /* The BSDF, its sampling and the light sample's cosine all use the mapped
   * normal (docs/accuracy.md "Normal maps"). */
  lux_surface_normal_map(&s, &m, textures, texels, tangents, hit.prim, hit.u, hit.v);
#endif
  LuxSurface sf = s;
  if (dot(wo, sf.ng) < 0.0f) {
    sf.ng = -sf.ng;
    sf.ns = -sf.ns;
  }
  float3 t, b;
  lux_onb(sf.ns, &t, &b);
  float3 wo_local = lux_to_local(wo, t, b, sf.ns);
  /* Shading normal facing away from the viewer (bent normals): clamp so the
   * BSDF stays defined. */
  if (wo_local.z <= 1e-4f) wo_local = normalize((float3)(wo_local.x, wo_local.y, 1e-4f));
  const LuxBsdf bsdf =
      lux_make_bsdf(base, metallic, roughness, m.specular.xyz, m.specular.w, wo_local.z);

  /* Extension ray (Eq. 6.2: one layer chosen stochastically). */
  const uint dim = LUX_DIM_VERTEX(path.depth);
  const float u_layer = lux_sample_1d(path.sample_index, dim + LUX_DIM_LAYER, path.seed);
  const float2 u_dir = lux_sample_2d(path.sample_index, dim + LUX_DIM_DIRECTION, path.seed);
  float3 wi_local, bsdf_weight;
  float pdf;
  const int layer = lux_bsdf_sample(&bsdf, wo_local, u_layer, u_dir, &wi_local, &bsdf_weight, &pdf);

#if LUX_RADIANCE_CACHE
  /* Final gather at the first hit (bake/radiance_cache.h): the light
   * sample here is weighted against the sensor's density (the path ends
   * here), and the hit reflects the rest of the irradiance its texel has
   * cached, A(wo) E / pi, with A(wo) estimated by the BSDF sample's weight.
   * A failed BSDF sample (weight 0) gathers nothing from the cache, as it
   * would trace nothing. */
  float3 e;
  const int gather = path.depth == 1u && path.uncached.w == 0.0f && dot(wo, s.ng_front) > 0.0f &&
                     lux_cache_gathers_at(&bsdf) &&
                     lux_cache_lookup(params, tris, atlas_uvs, covered, radiance_cache, hit.prim,
                                      hit.u, hit.v, hit.t, &e);
#else
  const int gather = 0;
#endif
  LuxRay shadow;
  float3 contribution;
  int unused_analytic;
  float3 unused_analytic_e;
  lux_next_event(params LUX_GROUP_ARGS(scene) LUX_GROUP_ARGS(textures) LUX_GROUP_ARGS(lights), &sf,
                 gather ? LUX_NEE_AT_PATH_END : LUX_NEE_AT_VERTEX, &bsdf, t, b, sf.ns, wo_local,
                 throughput, path.sample_index, dim, path.seed, 0, 0.0f, &shadow, &contribution,
                 &unused_analytic, &unused_analytic_e);
  shadow_rays[slot] = shadow;
#if LUX_RADIANCE_CACHE
  /* w = 1 marks the last bounce's light sample, which the cache leaves
   * out (resolve_shadows). */
  shadow_contrib[slot] = (float4)(contribution, path.depth == params.max_bounces ? 1.0f : 0.0f);
  if (gather) {
    if (layer >= 0 && lux_finite3(bsdf_weight))
      path.radiance.xyz += throughput * bsdf_weight * e * LUX_INV_PI;
    path.alive = 0u;
    paths[slot] = path;
    rays[slot] = lux_no_ray();
    return;
  }
#else
  shadow_contrib[slot] = (float4)(contribution, 0.0f);
#endif
  const float3 wi = lux_to_world(wi_local, t, b, sf.ns);
  int ok = layer >= 0 && pdf > 0.0f && dot(wi, sf.ng) > 0.0f && lux_finite3(bsdf_weight);
  throughput *= bsdf_weight;
  /* Russian roulette (§5.1) on the throughput relative to the sensor's pi. */
  if (ok && path.depth >= params.rr_depth) {
    const float q = fmin(0.95f, lux_max3(throughput) / LUX_SENSOR_WEIGHT);
    const float u_rr = lux_independent_1d(path.sample_index, dim + LUX_DIM_ROULETTE, path.seed);
    if (u_rr >= q)
      ok = 0;
    else
      throughput /= q;
  }
  path.throughput = (float4)(throughput, pdf);
  /* w: the guide's record of the first segment (kernels/shared/bake.h). */
  path.prev_pos = (float4)(sf.p, path.prev_pos.w);
  path.prev_normal = (float4)(sf.ns, path.prev_normal.w);
  path.alive = ok ? 1u : 0u;
  paths[slot] = path;
  rays[slot] =
      ok ? lux_make_ray(lux_offset_origin(sf.p, sf.ng, wi, params.offset_scale), wi, INFINITY)
         : lux_no_ray();
  alive[j] = path.alive;
#if LUX_SORT_DIRECTIONS
  tagged[j] = lux_tag_slot(slot, wi);
#endif
}

#endif /* LUXEL_BAKE_SHADE_H */
