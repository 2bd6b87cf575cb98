/* The surface BSDF: glTF metallic-roughness as an additive pair of layers,
 * Lambertian diffuse + GGX specular (thesis §6.3.1, "Sampling Real-Time
 * Material Models"), sampled one layer at a time (Eq. 6.2).
 *
 * Conventions: everything is in the local shading frame (z = shading
 * normal); wo points towards the viewer / previous path vertex, wi is the
 * sampled or lit direction; both unit length. Every function returns 0 (or
 * -1 for lux_bsdf_sample) when wo or wi is at or below the horizon: callers
 * flip the frame for two-sided materials before calling.
 *
 * Layers (index 0 diffuse, 1 specular):
 *   specular  f = F(wo.h) D(h) G2(wo, wi) / (4 wo.z wi.z), GGX D, Smith
 *             height-correlated G2 (Heitz 2014), Schlick F with
 *             f0 = mix(0.04, base_color, metallic).
 *   diffuse   f = diffuse / pi * (1 - F(wo.z)),  diffuse = base_color (1 - metallic).
 *             The (1 - F(wo.z)) factor removes the light a smooth coating
 *             reflects towards wo, so a white dielectric does not reflect
 *             1 + F: for a smooth coating the two layers sum to exactly 1.
 *             A rough coating reflects less than F(wo.z) (single-scattering
 *             GGX loses energy to masking), so the sum falls below 1 towards
 *             grazing (white, roughness 1: albedo 0.97 at wo.z = 1, 0.68 at
 *             0.2, 0.28 at 0.05) and exceeds it nowhere by more than ~1e-3
 *             (Jensen excess of the convex F, roughness 0.1..0.4, wo.z
 *             0.5..0.7). Without LUX_SPECULAR there is no coating and the
 *             diffuse layer is plain Lambert.
 *   alpha     = roughness^2, at least LUX_BSDF_MIN_ALPHA so roughness 0 is a
 *             very sharp but finite lobe (D <= 1 / (pi alpha^2) ~ 3.2e5).
 *   p_specular  probability of sampling the specular layer:
 *             lum(f0) / (lum(f0) + lum(diffuse)), clamped to [0.1, 0.9] when
 *             both layers reflect something; 1 when the diffuse layer is
 *             black (metals); exactly 0 without LUX_SPECULAR, where all
 *             specular code compiles out.
 *
 * Sampling (Eq. 6.2): the layer is chosen with u_layer, then sampled on its
 * own: cosine hemisphere for diffuse, the GGX distribution of visible
 * normals (Heitz, "Sampling the GGX Distribution of Visible Normals", JCGT
 * 7(4), 2018) reflected about the sampled microfacet normal for specular.
 * The weight is that layer's f cos / (p_layer pdf_layer), not the sum of
 * both layers (the thesis's Figure 6.2: evaluating all layers for a sample
 * of one causes fireflies); the caller combines layers with NEE by MIS
 * using lux_bsdf_pdf_layer. */
#ifndef LUXEL_SHADING_BSDF_H
#define LUXEL_SHADING_BSDF_H

#include "sampling/warp.h"

#define LUX_BSDF_LAYER_DIFFUSE 0
#define LUX_BSDF_LAYER_SPECULAR 1
/* pbrt-v4 treats alpha < 1e-3 as a perfect mirror; this keeps it a lobe. */
#define LUX_BSDF_MIN_ALPHA 1e-3f
#define LUX_BSDF_MIN_P_LAYER 0.1f

typedef struct {
  float3 diffuse;   /* Lambert albedo, base_color (1 - metallic) */
  float3 f0;        /* Fresnel reflectance at normal incidence */
  float alpha;      /* GGX alpha = roughness^2 (>= LUX_BSDF_MIN_ALPHA) */
  float p_specular; /* probability of sampling the specular layer */
} LuxBsdf;

/* Rec. 709 luminance of linear RGB. */
inline float lux_luminance(float3 c) {
  return dot(c, (float3)(0.2126f, 0.7152f, 0.0722f));
}

inline float lux_saturate(float x) {
  return fmin(fmax(x, 0.0f), 1.0f);
}

inline LuxBsdf lux_make_bsdf(float3 base_color, float metallic, float roughness) {
  LuxBsdf m;
  base_color = fmax(base_color, (float3)(0.0f));
  metallic = lux_saturate(metallic);
  roughness = lux_saturate(roughness);
  m.diffuse = base_color * (1.0f - metallic);
  m.f0 = mix((float3)(0.04f), base_color, metallic);
  m.alpha = fmax(roughness * roughness, LUX_BSDF_MIN_ALPHA);
#if LUX_SPECULAR
  const float ls = lux_luminance(m.f0), ld = lux_luminance(m.diffuse);
  m.p_specular = (ls + ld > 0.0f) ? ls / (ls + ld) : 0.5f;
  if (ls > 0.0f && ld > 0.0f)
    m.p_specular = clamp(m.p_specular, LUX_BSDF_MIN_P_LAYER, 1.0f - LUX_BSDF_MIN_P_LAYER);
#else
  m.p_specular = 0.0f;
#endif
  return m;
}

#if LUX_SPECULAR

/* Schlick's Fresnel approximation. */
inline float3 lux_fresnel_schlick(float3 f0, float cos_theta) {
  const float c = 1.0f - lux_saturate(cos_theta);
  const float c2 = c * c;
  return f0 + (1.0f - f0) * (c2 * c2 * c);
}

/* GGX (Trowbridge-Reitz) normal distribution for a unit half vector h with
 * h.z > 0. Written with sin^2 = h.x^2 + h.y^2 instead of 1 - cos^2 so a tiny
 * alpha keeps its precision at the peak. */
inline float lux_ggx_d(float3 h, float alpha) {
  const float a2 = alpha * alpha;
  const float t = (h.x * h.x + h.y * h.y) / a2 + h.z * h.z;
  return 1.0f / (LUX_PI * a2 * t * t);
}

/* Smith Lambda for GGX: (sqrt(1 + alpha^2 tan^2) - 1) / 2, in a form without
 * cancellation; z is floored so a grazing w gives a huge but finite value. */
inline float lux_ggx_lambda(float3 w, float alpha) {
  const float a = alpha * alpha * (w.x * w.x + w.y * w.y) / fmax(w.z * w.z, 1e-30f);
  return a / (2.0f * (1.0f + sqrt(1.0f + a)));
}

inline float lux_ggx_g1(float3 w, float alpha) {
  return 1.0f / (1.0f + lux_ggx_lambda(w, alpha));
}

/* Height-correlated masking-shadowing (Heitz 2014, Eq. 99). */
inline float lux_ggx_g2(float3 wo, float3 wi, float alpha) {
  return 1.0f / (1.0f + lux_ggx_lambda(wo, alpha) + lux_ggx_lambda(wi, alpha));
}

/* Density of visible normals (Heitz 2018, Eq. 3): G1(wo) max(0, wo.h) D(h) / wo.z. */
inline float lux_ggx_vndf_pdf(float3 wo, float3 h, float alpha) {
  return lux_ggx_g1(wo, alpha) * fmax(dot(wo, h), 0.0f) * lux_ggx_d(h, alpha) / wo.z;
}

/* Samples a visible normal for wo (wo.z > 0); Heitz 2018, Listing 1: stretch
 * to the alpha = 1 configuration, sample the projected hemisphere, unstretch. */
inline float3 lux_ggx_sample_vndf(float3 wo, float alpha, float2 u) {
  const float3 vh = normalize((float3)(alpha * wo.x, alpha * wo.y, wo.z));
  const float len2 = vh.x * vh.x + vh.y * vh.y;
  const float3 t1 =
      len2 > 0.0f ? (float3)(-vh.y, vh.x, 0.0f) * rsqrt(len2) : (float3)(1.0f, 0.0f, 0.0f);
  const float3 t2 = cross(vh, t1);
  const float r = sqrt(u.x);
  const float phi = 2.0f * LUX_PI * u.y;
  const float p1 = r * cos(phi);
  const float s = 0.5f * (1.0f + vh.z);
  const float p2 = (1.0f - s) * sqrt(fmax(0.0f, 1.0f - p1 * p1)) + s * r * sin(phi);
  const float3 nh = p1 * t1 + p2 * t2 + sqrt(fmax(0.0f, 1.0f - p1 * p1 - p2 * p2)) * vh;
  return normalize((float3)(alpha * nh.x, alpha * nh.y, fmax(nh.z, 0.0f)));
}

#endif /* LUX_SPECULAR */

/* f of one layer (not multiplied by cos); 0 below the horizon. */
inline float3 lux_bsdf_eval_layer(const LuxBsdf* m, int layer, float3 wo, float3 wi) {
  if (wo.z <= 0.0f || wi.z <= 0.0f) return (float3)(0.0f);
  if (layer == LUX_BSDF_LAYER_DIFFUSE) {
#if LUX_SPECULAR
    return m->diffuse * LUX_INV_PI * (1.0f - lux_fresnel_schlick(m->f0, wo.z));
#else
    return m->diffuse * LUX_INV_PI;
#endif
  }
#if LUX_SPECULAR
  if (layer == LUX_BSDF_LAYER_SPECULAR) {
    const float3 h = normalize(wo + wi);
    const float d = lux_ggx_d(h, m->alpha);
    const float g = lux_ggx_g2(wo, wi, m->alpha);
    return lux_fresnel_schlick(m->f0, dot(wo, h)) * (d * g / (4.0f * wo.z * wi.z));
  }
#endif
  return (float3)(0.0f);
}

/* p_layer * pdf_layer(wi), solid angle; 0 below the horizon. The reflection
 * Jacobian 1 / (4 wo.h) cancels the wo.h of the visible-normal density. */
inline float lux_bsdf_pdf_layer(const LuxBsdf* m, int layer, float3 wo, float3 wi) {
  if (wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
  if (layer == LUX_BSDF_LAYER_DIFFUSE)
    return (1.0f - m->p_specular) * lux_cosine_hemisphere_pdf(wi.z);
#if LUX_SPECULAR
  if (layer == LUX_BSDF_LAYER_SPECULAR) {
    const float3 h = normalize(wo + wi);
    return m->p_specular * lux_ggx_g1(wo, m->alpha) * lux_ggx_d(h, m->alpha) / (4.0f * wo.z);
  }
#endif
  return 0.0f;
}

/* Eq. 6.2: picks the specular layer when u_layer < p_specular, samples it
 * with u and returns the layer index, or -1 when the sample is unusable
 * (wo or wi at or below the horizon, pdf 0). weight = f_layer cos / pdf,
 * pdf = lux_bsdf_pdf_layer(layer, wi). */
inline int lux_bsdf_sample(const LuxBsdf* m, float3 wo, float u_layer, float2 u, float3* wi,
                           float3* weight, float* pdf) {
  *weight = (float3)(0.0f);
  *pdf = 0.0f;
  if (wo.z <= 0.0f) return -1;
#if LUX_SPECULAR
  if (u_layer < m->p_specular) {
    const float3 h = lux_ggx_sample_vndf(wo, m->alpha, u);
    *wi = 2.0f * dot(wo, h) * h - wo;
    if ((*wi).z <= 0.0f) return -1;
    *pdf = lux_bsdf_pdf_layer(m, LUX_BSDF_LAYER_SPECULAR, wo, *wi);
    if (!(*pdf > 0.0f)) return -1;
    /* f cos / (p pdf) with D and the 4 wo.z wi.z cancelled: F G2 / (G1(wo) p). */
    const float3 hr = normalize(wo + *wi);
    *weight = lux_fresnel_schlick(m->f0, dot(wo, hr)) *
              (lux_ggx_g2(wo, *wi, m->alpha) / (lux_ggx_g1(wo, m->alpha) * m->p_specular));
    return LUX_BSDF_LAYER_SPECULAR;
  }
#else
  (void)u_layer;
#endif
  *wi = lux_cosine_hemisphere(u);
  if ((*wi).z <= 0.0f) return -1;
  *pdf = lux_bsdf_pdf_layer(m, LUX_BSDF_LAYER_DIFFUSE, wo, *wi);
  if (!(*pdf > 0.0f)) return -1;
  /* f cos / ((1 - p) cos / pi): the cosines and pi cancel. */
  *weight =
      lux_bsdf_eval_layer(m, LUX_BSDF_LAYER_DIFFUSE, wo, *wi) * (LUX_PI / (1.0f - m->p_specular));
  return LUX_BSDF_LAYER_DIFFUSE;
}

#endif /* LUXEL_SHADING_BSDF_H */
