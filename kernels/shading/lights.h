/* Light sampling for next-event estimation (thesis §6.1) and the pdfs that
 * multiple importance sampling needs (§6.3.2, eq. 6.3).
 *
 * A light is chosen with probability proportional to its power (§6.3.2:
 * "probability proportional to its intensity, omitting any spatial
 * considerations") in O(1) through the table's alias entries
 * (shading/distribution.h, lux_sample_alias), then a point or direction
 * on it is sampled. Layout, units, feature macros and the equirect mapping
 * are documented in shared/light.h.
 *
 * Using a sample: if lux_sample_light returns 1, trace a shadow ray from p
 * along wi up to dist (INFINITY for directional lights and the sky); if
 * unoccluded the contribution is
 *     radiance * f(wi) * |cos(n, wi)| / pdf
 * where pdf includes the selection probability. For is_delta samples (point,
 * spot, directional without angular radius) pdf is the selection
 * probability alone and radiance already includes 1/dist^2 and the spot
 * falloff. `mis` says whether a BSDF-sampled ray could also reach the same
 * emitter (emissive triangles, the sky): only then is the sample weighted
 * with MIS against the BSDF pdf. Sun discs (directional lights with an
 * angular radius) have a solid-angle pdf but mis = 0: rays that escape are
 * shaded with the sky only, so NEE is the sun's one estimator. */
#ifndef LUXEL_SHADING_LIGHTS_H
#define LUXEL_SHADING_LIGHTS_H

#include "sampling/warp.h"
#include "shading/distribution.h"
#include "shared/light.h"

typedef struct LuxLightSample {
  float3 wi;       /* unit direction from p towards the light */
  float dist;      /* distance to the sampled point; INFINITY for directional and sky */
  float3 radiance; /* see the header comment */
  float pdf;       /* solid angle, times the selection probability (delta: selection only) */
  int is_delta;
  int mis;      /* 1: the BSDF strategy can hit this emitter too; weight with MIS */
  int light;    /* index in the light table */
  int triangle; /* emissive triangles: world triangle id (TriangleSoup order), else -1 */
  float2 bary;  /* emissive triangles: barycentrics of v1 and v2 (like LuxHit u, v) */
} LuxLightSample;

/* Uniform direction in the cone of half-angle a around unit `axis`, given
 * one_minus_cos = 1 - cos(a). sampling/warp.h's lux_uniform_cone takes
 * cos(a), which a float cannot hold for the sun (a ~ 0.27 deg, 1 - cos ~ 1e-5:
 * the float cos keeps ~2 digits of it), so the table stores 1 - cos and this
 * warp starts from it. */
inline float3 lux_lights_uniform_cone(float2 u, float one_minus_cos, float3 axis) {
  const float h = u.x * one_minus_cos; /* 1 - cos(theta), uniform */
  const float sin_t = sqrt(max(h * (2.0f - h), 0.0f));
  const float2 cs = lux_cos_sin_2pi(u.y);
  float3 t, b;
  lux_onb(axis, &t, &b);
  return normalize(lux_to_world((float3)(cs.x * sin_t, cs.y * sin_t, 1.0f - h), t, b, axis));
}

/* ---- Sky mapping (shared/light.h, EQUIRECT MAPPING). ---- */

inline float3 lux_sky_to_local(const LuxSky sky, float3 d) {
  const float s = sky.rotation.x, c = sky.rotation.y;
  return (float3)(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
}

inline float3 lux_sky_to_world(const LuxSky sky, float3 l) {
  const float s = sky.rotation.x, c = sky.rotation.y;
  return (float3)(c * l.x + s * l.z, l.y, -s * l.x + c * l.z);
}

/* Image coordinates (s along a row, t down the rows) of a unit local
 * direction. */
inline float2 lux_sky_local_to_st(float3 l) {
  return (float2)(0.5f + atan2(l.x, -l.z) * (0.5f / M_PI_F),
                  acos(clamp(l.y, -1.0f, 1.0f)) / M_PI_F);
}

#if LUX_SKY_IMAGE
inline float3 lux_sky_texel(const LuxSky sky, const __global float* texels, float2 st) {
  const int col = clamp((int)(st.x * (float)sky.width), 0, sky.width - 1);
  const int row = clamp((int)(st.y * (float)sky.height), 0, sky.height - 1);
  return vload3((size_t)row * (size_t)sky.width + (size_t)col, texels);
}
#endif

#if LUX_SKY_IMAGE
/* The octahedral cell of a unit local-frame normal on a side x side grid
 * (Cigolle et al., JCGT 3(2), 2014, §3.1; shading/sky_distribution.h
 * builds one sky distribution per cell and mirrors this lookup). */
inline uint lux_sky_normal_bin(float3 n, int side) {
  const float l1 = fabs(n.x) + fabs(n.y) + fabs(n.z);
  float2 p = l1 > 0.0f ? (float2)(n.x, n.z) / l1 : (float2)(0.0f);
  if (n.y < 0.0f) {
    const float2 sgn = (float2)(p.x >= 0.0f ? 1.0f : -1.0f, p.y >= 0.0f ? 1.0f : -1.0f);
    p = (1.0f - fabs(p.yx)) * sgn;
  }
  const float2 uv = p * 0.5f + 0.5f;
  const int ix = clamp((int)(uv.x * (float)side), 0, side - 1);
  const int iy = clamp((int)(uv.y * (float)side), 0, side - 1);
  return (uint)(iy * side + ix);
}

/* Two-level sampling of the image sky for a receiver with world normal n
 * (shading/sky_distribution.h; layout in shared/light.h): a block
 * from the table of n's normal cell, then a texel of the block, each level
 * reusing the fraction of its random number left inside the chosen cell
 * (pbrt's SampleContinuous). Returns image (s, t) and the density with
 * respect to (s, t); 0 when n's cell sees no light at all. */
inline __global const float* lux_sky_block_table(const LuxSky sky,
                                                 const __global float* sky_block_cdfs, float3 n) {
  const uint bin = lux_sky_normal_bin(lux_sky_to_local(sky, n), sky.normal_bins);
  const size_t size = (size_t)(sky.blocks_y + 1) + (size_t)sky.blocks_y * (sky.blocks_x + 1);
  return sky_block_cdfs + (size_t)bin * size;
}

inline __global const float* lux_sky_texel_table(const LuxSky sky,
                                                 const __global float* sky_texel_cdfs, uint block) {
  const size_t size =
      (size_t)(sky.block_height + 1) + (size_t)sky.block_height * (sky.block_width + 1);
  return sky_texel_cdfs + (size_t)block * size;
}

inline float2 lux_sky_sample_st(const LuxSky sky, const __global float* sky_block_cdfs,
                                const __global float* sky_texel_cdfs, float3 n, float2 u,
                                float* pdf_st) {
  const uint nbx = (uint)sky.blocks_x, nby = (uint)sky.blocks_y;
  const uint bw = (uint)sky.block_width, bh = (uint)sky.block_height;
  float ux = clamp(u.x, 0.0f, LUX_ONE_MINUS_EPSILON), uy = clamp(u.y, 0.0f, LUX_ONE_MINUS_EPSILON);
  float p_by, p_bx, p_ty, p_tx;
  const __global float* blocks = lux_sky_block_table(sky, sky_block_cdfs, n);
  const uint by = lux_sample_cdf(blocks, nby, uy, &p_by);
  uy = lux_cdf_remap(blocks, by, uy);
  const __global float* block_row = blocks + (nby + 1u) + by * (nbx + 1u);
  const uint bx = lux_sample_cdf(block_row, nbx, ux, &p_bx);
  ux = lux_cdf_remap(block_row, bx, ux);
  const __global float* texels = lux_sky_texel_table(sky, sky_texel_cdfs, by * nbx + bx);
  const uint ty = lux_sample_cdf(texels, bh, uy, &p_ty);
  uy = lux_cdf_remap(texels, ty, uy);
  const __global float* texel_row = texels + (bh + 1u) + ty * (bw + 1u);
  const uint tx = lux_sample_cdf(texel_row, bw, ux, &p_tx);
  ux = lux_cdf_remap(texel_row, tx, ux);
  *pdf_st = p_by * p_bx * p_ty * p_tx * (float)sky.width * (float)sky.height;
  return (float2)(((float)(bx * bw + tx) + ux) / (float)sky.width,
                  ((float)(by * bh + ty) + uy) / (float)sky.height);
}

/* The density lux_sky_sample_st has at (s, t) for normal n. */
inline float lux_sky_pdf_st(const LuxSky sky, const __global float* sky_block_cdfs,
                            const __global float* sky_texel_cdfs, float3 n, float2 st) {
  const uint nbx = (uint)sky.blocks_x, nby = (uint)sky.blocks_y;
  const uint bw = (uint)sky.block_width, bh = (uint)sky.block_height;
  const uint x = min((uint)max(st.x * (float)sky.width, 0.0f), (uint)sky.width - 1u);
  const uint y = min((uint)max(st.y * (float)sky.height, 0.0f), (uint)sky.height - 1u);
  const uint bx = x / bw, by = y / bh, tx = x - bx * bw, ty = y - by * bh;
  const __global float* blocks = lux_sky_block_table(sky, sky_block_cdfs, n);
  const __global float* block_row = blocks + (nby + 1u) + by * (nbx + 1u);
  const __global float* texels = lux_sky_texel_table(sky, sky_texel_cdfs, by * nbx + bx);
  const __global float* texel_row = texels + (bh + 1u) + ty * (bw + 1u);
  return lux_cdf_pmf(blocks, by) * lux_cdf_pmf(block_row, bx) * lux_cdf_pmf(texels, ty) *
         lux_cdf_pmf(texel_row, tx) * (float)sky.width * (float)sky.height;
}
#endif

/* Radiance arriving from direction `dir` (towards the sky), for rays that
 * escape the scene. */
inline float3 lux_sky_radiance(LuxSky sky, const __global float* sky_texels, float3 dir) {
#if LUX_SKY_IMAGE
  if (sky.kind == LUX_SKY_KIND_IMAGE) {
    return lux_sky_texel(sky, sky_texels,
                         lux_sky_local_to_st(lux_sky_to_local(sky, normalize(dir))));
  }
#endif
#if LUX_SKY
  if (sky.kind == LUX_SKY_KIND_CONSTANT) return sky.radiance.xyz;
#endif
  (void)sky;
  (void)sky_texels;
  (void)dir;
  return (float3)(0.0f);
}

/* Solid-angle pdf with which lux_sample_light produces direction `dir` from
 * the sky at a point with normal n, including the sky's selection
 * probability (for MIS when a BSDF ray escapes: n is the normal that vertex
 * used for its light sample). sky_light: the sky's light index (LuxSky.light). */
inline float lux_sky_pdf(LuxSky sky, const __global LuxAliasEntry* light_select, int sky_light,
                         const __global float* sky_block_cdfs, const __global float* sky_texel_cdfs,
                         float3 dir, float3 n) {
  if (sky_light < 0) return 0.0f;
  const float select = light_select[sky_light].pmf;
#if LUX_SKY_IMAGE
  if (sky.kind == LUX_SKY_KIND_IMAGE) {
    const float3 l = lux_sky_to_local(sky, normalize(dir));
    const float sin_t = sqrt(max(1.0f - l.y * l.y, 0.0f));
    if (!(sin_t > 0.0f)) return 0.0f;
    /* d(omega) = sin(theta) d(theta) d(phi) = 2 pi^2 sin(theta) ds dt */
    const float pdf_st =
        lux_sky_pdf_st(sky, sky_block_cdfs, sky_texel_cdfs, n, lux_sky_local_to_st(l));
    return select * pdf_st / (2.0f * M_PI_F * M_PI_F * sin_t);
  }
#endif
#if LUX_SKY
  if (sky.kind == LUX_SKY_KIND_CONSTANT) {
    const float cos_n = dot(normalize(dir), n);
    return cos_n > 0.0f ? select * cos_n * M_1_PI_F : 0.0f;
  }
#endif
  (void)sky_block_cdfs;
  (void)sky_texel_cdfs;
  (void)dir;
  (void)n;
  return 0.0f;
}

/* ---- Per-type samplers: fill wi, dist, radiance, pdf (without selection),
 * flags; return 0 when the sample carries nothing. ---- */

#if LUX_LIGHT_POINT || LUX_LIGHT_SPOT
/* Direction and inverse-square falloff towards a point source. */
inline int lux_lights_towards_point(const LuxLight* light, float3 p, LuxLightSample* s,
                                    float* inv_d2) {
  const float3 to = light->origin.xyz - p;
  const float d2 = dot(to, to);
  if (!(d2 > 0.0f)) return 0;
  s->dist = sqrt(d2);
  s->wi = to / s->dist;
  s->pdf = 1.0f;
  s->is_delta = 1;
  *inv_d2 = 1.0f / d2;
  return 1;
}
#endif

#if LUX_LIGHT_POINT
inline int lux_lights_sample_point(const LuxLight* light, float3 p, LuxLightSample* s) {
  float inv_d2;
  if (!lux_lights_towards_point(light, p, s, &inv_d2)) return 0;
  s->radiance = light->emission.xyz * inv_d2;
  return 1;
}
#endif

#if LUX_LIGHT_SPOT
/* glTF KHR_lights_punctual falloff: the square of a linear ramp in cos from
 * the outer to the inner cone. */
inline int lux_lights_sample_spot(const LuxLight* light, float3 p, LuxLightSample* s) {
  float inv_d2;
  if (!lux_lights_towards_point(light, p, s, &inv_d2)) return 0;
  const float cos_inner = LUX_LIGHT_COS_INNER(*light), cos_outer = LUX_LIGHT_COS_OUTER(*light);
  const float cd = dot(light->axis.xyz, -s->wi);
  float att = clamp((cd - cos_outer) / max(cos_inner - cos_outer, 1e-4f), 0.0f, 1.0f);
  att *= att;
  if (!(att > 0.0f)) return 0;
  s->radiance = light->emission.xyz * (att * inv_d2);
  return 1;
}
#endif

#if LUX_LIGHT_DIRECTIONAL
inline int lux_lights_sample_directional(const LuxLight* light, float2 u, LuxLightSample* s) {
  const float3 to_light = -light->axis.xyz;
  const float one_minus_cos = LUX_LIGHT_ONE_MINUS_COS(*light);
  s->dist = INFINITY;
  s->radiance = light->emission.xyz;
  if (one_minus_cos > 0.0f) {
    s->wi = lux_lights_uniform_cone(u, one_minus_cos, to_light);
    s->pdf = 1.0f / (2.0f * M_PI_F * one_minus_cos);
  } else {
    s->wi = to_light;
    s->pdf = 1.0f;
    s->is_delta = 1;
  }
  return 1;
}
#endif

#if LUX_LIGHT_EMISSIVE
/* Uniform by area, converted to solid angle: pdf = d^2 / (A |cos theta_l|). */
inline int lux_lights_sample_triangle(const LuxLight* light, float3 p, float2 u,
                                      LuxLightSample* s) {
  const float2 bary = lux_uniform_triangle(u); /* area-uniform (b1, b2) */
  const float3 x = light->origin.xyz + bary.x * light->axis.xyz + bary.y * light->edge2.xyz;
  const float3 to = x - p;
  const float d2 = dot(to, to);
  if (!(d2 > 0.0f)) return 0;
  s->dist = sqrt(d2);
  s->wi = to / s->dist;
  float cos_l = -dot(light->shape.xyz, s->wi);
  if (LUX_LIGHT_FLAGS(*light) & LUX_LIGHT_FLAG_DOUBLE_SIDED) cos_l = fabs(cos_l);
  if (!(cos_l > 0.0f)) return 0; /* p sees the back of a one-sided emitter */
  s->pdf = d2 / (LUX_LIGHT_AREA(*light) * cos_l);
  s->radiance = light->emission.xyz;
  s->mis = 1;
  s->triangle = LUX_LIGHT_TRIANGLE(*light);
  s->bary = bary;
  return 1;
}
#endif

#if LUX_SKY || LUX_SKY_IMAGE
inline int lux_lights_sample_sky(const LuxSky sky, const __global float* sky_texels,
                                 const __global float* sky_block_cdfs,
                                 const __global float* sky_texel_cdfs, float3 n, float2 u,
                                 LuxLightSample* s) {
  s->dist = INFINITY;
  s->mis = 1;
#if LUX_SKY_IMAGE
  if (sky.kind == LUX_SKY_KIND_IMAGE) {
    float pdf_st;
    const float2 st = lux_sky_sample_st(sky, sky_block_cdfs, sky_texel_cdfs, n, u, &pdf_st);
    /* theta = pi st.y, phi = 2 pi (st.x - 1/2), through sinpi/cospi
     * (sampling/warp.h, lux_cos_sin_2pi). */
    const float sin_t = sinpi(st.y);
    if (!(pdf_st > 0.0f) || !(sin_t > 0.0f)) return 0;
    const float2 cs_phi = lux_cos_sin_2pi(st.x - 0.5f);
    s->wi = lux_sky_to_world(sky, (float3)(sin_t * cs_phi.y, cospi(st.y), -sin_t * cs_phi.x));
    s->pdf = pdf_st / (2.0f * M_PI_F * M_PI_F * sin_t);
    s->radiance = lux_sky_texel(sky, sky_texels, st);
    return 1;
  }
#endif
#if LUX_SKY
  if (sky.kind == LUX_SKY_KIND_CONSTANT) {
    /* Cosine-weighted about the receiver's normal: the constant sky below
     * the surface adds nothing, and L cos / pdf = pi L is then the same for
     * every sample (zero variance where nothing occludes). */
    const float3 l = lux_cosine_hemisphere(u);
    if (!(l.z > 0.0f)) return 0;
    float3 t, b;
    lux_onb(n, &t, &b);
    s->wi = lux_to_world(l, t, b, n);
    s->pdf = l.z * M_1_PI_F;
    s->radiance = sky.radiance.xyz;
    return 1;
  }
#endif
  (void)sky_texels;
  (void)sky_block_cdfs;
  (void)sky_texel_cdfs;
  return 0;
}
#endif

/* Samples light `index`, chosen with probability `select`, from shading
 * point p with normal n (see lux_sample_light). */
inline int lux_sample_light_at(const __global LuxLight* lights, uint index, float select,
                               LuxSky sky, const __global float* sky_texels,
                               const __global float* sky_block_cdfs,
                               const __global float* sky_texel_cdfs, float3 p, float3 n, float2 u,
                               LuxLightSample* out) {
  out->wi = (float3)(0.0f, 1.0f, 0.0f);
  out->dist = 0.0f;
  out->radiance = (float3)(0.0f);
  out->pdf = 0.0f;
  out->is_delta = 0;
  out->mis = 0;
  out->light = -1;
  out->triangle = -1;
  out->bary = (float2)(0.0f);
  if (!(select > 0.0f)) return 0;
  const LuxLight light = lights[index];
  out->light = (int)index;
  int ok = 0;
  switch (LUX_LIGHT_TYPE(light)) {
#if LUX_LIGHT_POINT
    case LUX_LIGHT_TYPE_POINT:
      ok = lux_lights_sample_point(&light, p, out);
      break;
#endif
#if LUX_LIGHT_SPOT
    case LUX_LIGHT_TYPE_SPOT:
      ok = lux_lights_sample_spot(&light, p, out);
      break;
#endif
#if LUX_LIGHT_DIRECTIONAL
    case LUX_LIGHT_TYPE_DIRECTIONAL:
      ok = lux_lights_sample_directional(&light, u, out);
      break;
#endif
#if LUX_LIGHT_EMISSIVE
    case LUX_LIGHT_TYPE_TRIANGLE:
      ok = lux_lights_sample_triangle(&light, p, u, out);
      break;
#endif
#if LUX_SKY || LUX_SKY_IMAGE
    case LUX_LIGHT_TYPE_SKY:
      ok = lux_lights_sample_sky(sky, sky_texels, sky_block_cdfs, sky_texel_cdfs, n, u, out);
      break;
#endif
    default:
      break;
  }
  (void)p;
  (void)u;
  (void)sky;
  (void)sky_texels;
  (void)sky_block_cdfs;
  (void)sky_texel_cdfs;
  if (!ok || !(out->pdf > 0.0f)) return 0;
  out->pdf *= select;
  return 1;
}

/* Next-event estimation: pick a light by power with u_select, sample it with
 * u from shading point p with normal n (the constant sky is sampled about n;
 * lux_sky_pdf needs the same n). Returns 0 when the sample carries nothing (no
 * lights, p behind a one-sided emitter, outside a spot cone, a compiled-out
 * light type). */
inline int lux_sample_light(const __global LuxLight* lights,
                            const __global LuxAliasEntry* light_select, uint light_count,
                            LuxSky sky, const __global float* sky_texels,
                            const __global float* sky_block_cdfs,
                            const __global float* sky_texel_cdfs, float3 p, float3 n,
                            float u_select, float2 u, LuxLightSample* out) {
  float select = 0.0f;
  const uint index =
      light_count == 0u ? 0u : lux_sample_alias(light_select, light_count, u_select, &select);
  return lux_sample_light_at(lights, index, select, sky, sky_texels, sky_block_cdfs, sky_texel_cdfs,
                             p, n, u, out);
}

/* Solid-angle pdf with which lux_sample_light would produce the point
 * hit_point on emissive-triangle light `light` from p, selection included
 * (for MIS when a BSDF ray hits an emitter; triangle_light maps the hit
 * triangle to `light`). light_normal: the hit triangle's geometric normal
 * (any length, either sign). 0 for the back of a one-sided emitter. */
inline float lux_light_pdf_triangle(const __global LuxLight* lights,
                                    const __global LuxAliasEntry* light_select, int light, float3 p,
                                    float3 hit_point, float3 light_normal) {
#if LUX_LIGHT_EMISSIVE
  if (light < 0) return 0.0f;
  const LuxLight l = lights[light];
  if (LUX_LIGHT_TYPE(l) != LUX_LIGHT_TYPE_TRIANGLE) return 0.0f;
  const float3 to = hit_point - p;
  const float d2 = dot(to, to);
  if (!(d2 > 0.0f)) return 0.0f;
  const float3 wi = to * rsqrt(d2);
  if (!(LUX_LIGHT_FLAGS(l) & LUX_LIGHT_FLAG_DOUBLE_SIDED) && !(dot(l.shape.xyz, wi) < 0.0f))
    return 0.0f;
  const float cos_l = fabs(dot(normalize(light_normal), wi));
  if (!(cos_l > 0.0f)) return 0.0f;
  return light_select[light].pmf * d2 / (LUX_LIGHT_AREA(l) * cos_l);
#else
  (void)lights;
  (void)light_select;
  (void)light;
  (void)p;
  (void)hit_point;
  (void)light_normal;
  return 0.0f;
#endif
}

#endif /* LUXEL_SHADING_LIGHTS_H */
