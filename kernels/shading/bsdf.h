/* The surface BSDF: the glTF 2.0 metallic-roughness BRDF as the
 * specification's Appendix B defines it (glTF 2.0 specification, Appendix B
 * "BRDF Implementation", B.3 "Metal BRDF and Dielectric BSDF"), plus the
 * Kulla-Conty multiple-scattering energy compensation of the GGX lobe
 * (Kulla & Conty 2017, "Revisiting Physically Based Shading at Imageworks",
 * SIGGRAPH course slides, "Energy compensation" and "Fresnel"), sampled one
 * layer at a time (thesis §6.3.1, Eq. 6.2).
 *
 * Conventions: everything is in the local shading frame (z = shading
 * normal); wo points towards the viewer / previous path vertex, wi is the
 * sampled or lit direction; both unit length. Every function returns 0 (or
 * -1 for lux_bsdf_sample) when wo or wi is at or below the horizon: callers
 * flip the frame for two-sided materials before calling. The BSDF is built
 * for one wo (lux_make_bsdf takes wo.z): the compensation and the layer
 * probability depend on it.
 *
 * Appendix B, with h = normalize(wo + wi), alpha = roughness^2:
 *   specular_brdf = D(h) G2(wo, wi) / (4 wo.z wi.z), GGX D, Smith
 *                   height-correlated G2 (Heitz 2014, "Understanding the
 *                   Masking-Shadowing Function", Eq. 99)
 *   metal         = conductor_fresnel(f0 = base_color, specular_brdf)
 *                 = specular_brdf * Schlick(base_color, wo.h)
 *   dielectric    = fresnel_mix(ior 1.5, base = base_color / pi, layer = specular_brdf)
 *                 = mix(base_color / pi, specular_brdf, Schlick(0.04, wo.h))
 *   f             = mix(dielectric, metal, metallic)
 * which this file evaluates exactly, as two layers:
 *   specular  Schlick(f0, wo.h) specular_brdf, f0 = mix(0.04, base_color,
 *             metallic) (the mix is linear in f0, so this is exact);
 *   diffuse   diffuse / pi * (1 - Schlick(0.04, wo.h)), diffuse =
 *             base_color (1 - metallic): the dielectric's own (1 - F) with the
 *             same F(wo.h) as its specular layer (not the mixed f0: Appendix
 *             B mixes the two whole BRDFs), plus the compensation lobe below.
 *   alpha     = roughness^2, at least LUX_BSDF_MIN_ALPHA so roughness 0 is a
 *             very sharp but finite lobe (D <= 1 / (pi alpha^2) ~ 3.2e5).
 *
 * Energy compensation (Kulla-Conty 2017): single-scattering GGX with F = 1
 * reflects only E(mu_o) (E_avg on average) of the light; the rest would
 * scatter again between microfacets. The lobe
 *   f_ms = (1 - E(wo.z)) (1 - E(wi.z)) / (pi (1 - E_avg))
 * reflects exactly 1 - E(wo.z), so f_ss + f_ms is a white furnace of 1 for
 * F = 1. With Fresnel, f_ms is scaled by the colour
 *   F_ms = F_avg^2 E_avg / (1 - F_avg (1 - E_avg)),   F_avg = (20 f0 + 1) / 21
 * (the slides' series of interreflections; F_avg = 2 int F(mu) mu dmu is
 * exact for Schlick's F), mixed like Appendix B: (1 - metallic) F_ms(0.04) +
 * metallic F_ms(base_color). E and E_avg come from the generated
 * ggx_albedo_table.h (bilinear in (wo.z, roughness); E_avg is the exact
 * average of the interpolated rows, so the lobe conserves energy exactly
 * against the table). f_ms belongs to layer 0 with the diffuse lobe; layer
 * 0 is sampled as a one-sample mixture (p_cosine) of the cosine hemisphere
 * and the compensation lobe's own tabulated distribution
 * (lux_ggx_ms_sample), and its pdf is that mixture.
 *
 * KHR_materials_specular: the dielectric's Fresnel becomes
 *   F_d(wo.h) = f0_d + (f90_d - f0_d) (1 - wo.h)^5,
 *   f0_d = min(F0(ior) specularColor, 1) specular, f90_d = specular
 * (LuxMaterial.specular; f0_d = F0(ior) and f90_d = 1 without the
 * extension), a colour. The specular layer's Fresnel is mix(F_d, Schlick
 * metal, metallic), which is again Schlick's form with f0 = mix(f0_d,
 * base_color, metallic) and f90 = mix(f90_d, 1, metallic); the diffuse is
 * weighted by 1 - F_d per channel; F_avg = f0 + (f90 - f0) / 21 in the
 * compensation.
 *
 * Deviations from Appendix B, measured in docs/accuracy.md: the added
 * compensation lobe (Appendix B is single-scattering); Appendix B's own
 * dielectric is not energy conserving (its diffuse (1 - F(wo.h)) does not
 * equal the light the coating's GGX lobe leaves: a smooth white dielectric
 * reflects up to ~1.9 at grazing wo), kept as specified; scenes whose
 * materials are all rough dielectrics (metallic 0, roughness 1, no texture)
 * compile the specular layer out and are exactly Lambertian (their 4 %
 * coating is left out).
 *
 * Layers (index 0 diffuse + compensation; 1 specular):
 *   p_specular  probability of sampling the specular layer: ls / (ls + lc),
 *             ls = lum(f0) E(wo.z) (the single-scattering albedo at normal
 *             Fresnel), lc = lum(diffuse) + lum(F_ms) (1 - E(wo.z)); clamped
 *             to [0.1, 0.9] when the diffuse layer reflects something; 1 for
 *             a smooth metal (no compensation to sample); exactly 0 without
 *             LUX_SPECULAR, where all specular code compiles out and the
 *             diffuse layer is plain Lambert.
 *   p_cosine  within layer 0, the probability of cosine sampling:
 *             lum(diffuse) / lc; the rest samples the compensation lobe
 *             (1 for no compensation, 0 for a metal).
 *
 * Sampling (Eq. 6.2): the layer is chosen with u_layer, then sampled on its
 * own: layer 0 by the cosine hemisphere / compensation mixture (u_layer,
 * rescaled, picks the component), the specular layer by the GGX
 * distribution of visible normals (Heitz, "Sampling the GGX Distribution of
 * Visible Normals", JCGT 7(4), 2018) reflected about the sampled microfacet
 * normal.
 * The weight is that layer's f cos / (p_layer pdf_layer), not the sum of
 * both layers (the thesis's Figure 6.2: evaluating all layers for a sample
 * of one causes fireflies); the caller combines layers with NEE by MIS
 * using lux_bsdf_pdf_layer. */
#ifndef LUXEL_SHADING_BSDF_H
#define LUXEL_SHADING_BSDF_H

#include "sampling/warp.h"
#if LUX_SPECULAR
#include "shading/ggx_albedo_table.h"
#endif

#define LUX_BSDF_LAYER_DIFFUSE 0
#define LUX_BSDF_LAYER_SPECULAR 1
/* pbrt-v4 treats alpha < 1e-3 as a perfect mirror; this keeps it a lobe. */
#define LUX_BSDF_MIN_ALPHA 1e-3f
#define LUX_BSDF_MIN_P_LAYER 0.1f
/* Appendix B's dielectric: ior 1.5, f0 = ((1.5 - 1) / (1.5 + 1))^2. A
 * material's KHR_materials_ior changes it (LuxMaterial.dielectric_f0). */
#define LUX_BSDF_DIELECTRIC_F0 0.04f

typedef struct {
  float3 diffuse;       /* Lambert albedo, base_color (1 - metallic) */
  float3 f0;            /* Fresnel reflectance at normal incidence */
  float f90;            /* ... and at grazing incidence */
  float3 f0_dielectric; /* f0 of the dielectric layer (weights the diffuse) */
  float f90_dielectric; /* f90 of the dielectric layer */
  float3 ms;            /* F_ms (1 - E(wo.z)) / (pi (1 - E_avg)): f_ms = ms (1 - E(wi.z)) */
  float alpha;          /* GGX alpha = roughness^2 (>= LUX_BSDF_MIN_ALPHA) */
  float roughness;      /* saturated roughness, the table coordinate */
  float p_specular;     /* probability of sampling the specular layer */
  float p_cosine;       /* within layer 0: probability of cosine (vs compensation) sampling */
} LuxBsdf;

/* Rec. 709 luminance of linear RGB. */
inline float lux_luminance(float3 c) {
  return dot(c, (float3)(0.2126f, 0.7152f, 0.0722f));
}

inline float lux_saturate(float x) {
  return fmin(fmax(x, 0.0f), 1.0f);
}

inline float lux_max3_bsdf(float3 v) {
  return fmax(v.x, fmax(v.y, v.z));
}

#if LUX_SPECULAR

/* E(mu, roughness) of ggx_albedo_table.h, bilinear in (sqrt(mu), roughness)
 * between the nodes. */
inline float lux_ggx_albedo(float mu, float roughness) {
  const float n = (float)(LUX_GGX_ALBEDO_SIZE - 1);
  const float x = sqrt(lux_saturate(mu)) * n, y = lux_saturate(roughness) * n;
  const int i = min((int)x, LUX_GGX_ALBEDO_SIZE - 2), j = min((int)y, LUX_GGX_ALBEDO_SIZE - 2);
  const float tx = x - (float)i, ty = y - (float)j;
  const int k = j * LUX_GGX_ALBEDO_SIZE + i;
  const float e0 = mix(lux_ggx_e[k], lux_ggx_e[k + 1], tx);
  const float e1 =
      mix(lux_ggx_e[k + LUX_GGX_ALBEDO_SIZE], lux_ggx_e[k + LUX_GGX_ALBEDO_SIZE + 1], tx);
  return mix(e0, e1, ty);
}

/* E_avg(roughness), linear between the nodes (the exact average of the
 * bilinear E above). */
inline float lux_ggx_albedo_avg(float roughness) {
  const float y = lux_saturate(roughness) * (float)(LUX_GGX_ALBEDO_SIZE - 1);
  const int j = min((int)y, LUX_GGX_ALBEDO_SIZE - 2);
  return mix(lux_ggx_e_avg[j], lux_ggx_e_avg[j + 1], y - (float)j);
}

/* Kulla-Conty 2017 ("Fresnel"): the colour of the multiply scattered light,
 * F_avg^2 E_avg / (1 - F_avg (1 - E_avg)), with Schlick's
 * F_avg = 2 int F mu dmu = f0 + (f90 - f0) / 21. */
inline float3 lux_kulla_conty_fms(float3 f0, float f90, float e_avg) {
  const float3 f_avg = f0 + (f90 - f0) * (1.0f / 21.0f);
  return f_avg * f_avg * e_avg / (1.0f - f_avg * (1.0f - e_avg));
}

/* Sampling the compensation lobe (shape (1 - E(mu)) mu): a roughness row
 * is picked with the weights of the bilinear E, a cell of sqrt(mu) from the
 * row's tabulated cumulative distribution lux_ggx_ms_cdf, mu within the cell
 * proportionally to mu (mu^2 uniform), phi uniformly. The density over
 * solid angle is, on cell i, ((1 - t) c_j,i + t c_j+1,i) mu / (pi (1 - E_avg))
 * with c_j,i = dcdf (1 - E_avg_j) / (x_i+1^4 - x_i^4) (the cell's mean of
 * 1 - E), exactly what lux_ggx_ms_pdf returns. */
inline float lux_ggx_ms_cell_density(int row, int cell) {
  const int k = row * (LUX_GGX_ALBEDO_SIZE - 1) + cell;
  const float lo = cell > 0 ? lux_ggx_ms_cdf[k - 1] : 0.0f;
  const float h = 1.0f / (float)(LUX_GGX_ALBEDO_SIZE - 1);
  const float xa = (float)cell * h, xb = (float)(cell + 1) * h;
  const float xa2 = xa * xa, xb2 = xb * xb;
  return (lux_ggx_ms_cdf[k] - lo) * (1.0f - lux_ggx_e_avg[row]) / (xb2 * xb2 - xa2 * xa2);
}

inline float lux_ggx_ms_pdf(float roughness, float mu) {
  if (mu <= 0.0f) return 0.0f;
  const float n = (float)(LUX_GGX_ALBEDO_SIZE - 1);
  const float y = lux_saturate(roughness) * n;
  const int j = min((int)y, LUX_GGX_ALBEDO_SIZE - 2);
  const float t = y - (float)j;
  const int i = min((int)(sqrt(fmin(mu, 1.0f)) * n), LUX_GGX_ALBEDO_SIZE - 2);
  const float lost = mix(1.0f - lux_ggx_e_avg[j], 1.0f - lux_ggx_e_avg[j + 1], t);
  const float c = mix(lux_ggx_ms_cell_density(j, i), lux_ggx_ms_cell_density(j + 1, i), t);
  return lost > 0.0f ? c * mu * LUX_INV_PI / lost : 0.0f;
}

inline float3 lux_ggx_ms_sample(float roughness, float u_row, float2 u) {
  const float n = (float)(LUX_GGX_ALBEDO_SIZE - 1);
  const float y = lux_saturate(roughness) * n;
  int j = min((int)y, LUX_GGX_ALBEDO_SIZE - 2);
  const float t = y - (float)j;
  const float w0 = (1.0f - t) * (1.0f - lux_ggx_e_avg[j]), w1 = t * (1.0f - lux_ggx_e_avg[j + 1]);
  if (u_row * (w0 + w1) >= w0) ++j;
  const int base = j * (LUX_GGX_ALBEDO_SIZE - 1);
  int i = 0;
  while (i < LUX_GGX_ALBEDO_SIZE - 2 && u.x >= lux_ggx_ms_cdf[base + i]) ++i;
  const float lo = i > 0 ? lux_ggx_ms_cdf[base + i - 1] : 0.0f, hi = lux_ggx_ms_cdf[base + i];
  const float s = hi > lo ? lux_saturate((u.x - lo) / (hi - lo)) : 0.5f;
  const float xa = (float)i / n, xb = (float)(i + 1) / n;
  const float mu = sqrt(mix(xa * xa * xa * xa, xb * xb * xb * xb, s));
  const float sin_theta = sqrt(fmax(0.0f, 1.0f - mu * mu));
  const float2 cs = lux_cos_sin_2pi(u.y);
  return (float3)(sin_theta * cs.x, sin_theta * cs.y, mu);
}

#endif /* LUX_SPECULAR */

/* wo_z: cos theta of the direction the BSDF will be used with (the
 * compensation and p_specular depend on it); callers clamp it above 0. */
inline LuxBsdf lux_make_bsdf(float3 base_color, float metallic, float roughness,
                             float3 dielectric_f0, float dielectric_f90, float wo_z) {
  LuxBsdf m;
  base_color = fmax(base_color, (float3)(0.0f));
  metallic = lux_saturate(metallic);
  roughness = lux_saturate(roughness);
  m.diffuse = base_color * (1.0f - metallic);
  dielectric_f0 = fmin(fmax(dielectric_f0, (float3)(0.0f)), (float3)(1.0f));
  dielectric_f90 = lux_saturate(dielectric_f90);
  m.f0_dielectric = dielectric_f0;
  m.f90_dielectric = dielectric_f90;
  m.f0 = mix(dielectric_f0, base_color, metallic);
  m.f90 = mix(dielectric_f90, 1.0f, metallic);
  m.alpha = fmax(roughness * roughness, LUX_BSDF_MIN_ALPHA);
  m.roughness = roughness;
  m.ms = (float3)(0.0f);
#if LUX_SPECULAR
  const float e_o = lux_ggx_albedo(wo_z, roughness);
  const float e_avg = lux_ggx_albedo_avg(roughness);
  /* The albedo of the compensation lobe at wo: F_ms (1 - E(wo.z)). */
  float3 ms_albedo = (float3)(0.0f);
  /* Keeps 1 / (1 - E_avg) finite; the smoothest row (roughness 0, alpha
   * 1e-3) still loses ~1e-5 on average, at grazing angles. */
  if (1.0f - e_avg > 1e-7f) {
    const float3 fms =
        (1.0f - metallic) * lux_kulla_conty_fms(dielectric_f0, dielectric_f90, e_avg) +
        metallic * lux_kulla_conty_fms(base_color, 1.0f, e_avg);
    ms_albedo = fms * fmax(1.0f - e_o, 0.0f);
    m.ms = ms_albedo * (LUX_INV_PI / (1.0f - e_avg));
  }
  const float ld = lux_luminance(m.diffuse);
  const float ls = lux_luminance(m.f0) * e_o, lc = ld + lux_luminance(ms_albedo);
  m.p_specular = (ls + lc > 0.0f) ? ls / (ls + lc) : 0.5f;
  if (ls > 0.0f && ld > 0.0f)
    m.p_specular = clamp(m.p_specular, LUX_BSDF_MIN_P_LAYER, 1.0f - LUX_BSDF_MIN_P_LAYER);
  /* Layer 0 is a one-sample mixture of cosine and compensation sampling in
   * proportion to the two lobes' albedos (no compensation: cosine only). */
  m.p_cosine = lc > 0.0f ? ld / lc : 1.0f;
  if (lux_max3_bsdf(m.ms) <= 0.0f) m.p_cosine = 1.0f;
#else
  (void)wo_z;
  m.p_specular = 0.0f;
  m.p_cosine = 1.0f;
#endif
  return m;
}

#if LUX_SPECULAR

/* Schlick's Fresnel approximation, f0 + (f90 - f0) (1 - cos)^5. */
inline float3 lux_fresnel_schlick(float3 f0, float f90, float cos_theta) {
  const float c = 1.0f - lux_saturate(cos_theta);
  const float c2 = c * c;
  return f0 + (f90 - f0) * (c2 * c2 * c);
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
  const float2 cs = lux_cos_sin_2pi(u.y);
  const float p1 = r * cs.x;
  const float s = 0.5f * (1.0f + vh.z);
  const float p2 = (1.0f - s) * sqrt(fmax(0.0f, 1.0f - p1 * p1)) + s * r * cs.y;
  const float3 nh = p1 * t1 + p2 * t2 + sqrt(fmax(0.0f, 1.0f - p1 * p1 - p2 * p2)) * vh;
  return normalize((float3)(alpha * nh.x, alpha * nh.y, fmax(nh.z, 0.0f)));
}

#endif /* LUX_SPECULAR */

/* f of one layer (not multiplied by cos); 0 below the horizon. */
inline float3 lux_bsdf_eval_layer(const LuxBsdf* m, int layer, float3 wo, float3 wi) {
  if (wo.z <= 0.0f || wi.z <= 0.0f) return (float3)(0.0f);
  if (layer == LUX_BSDF_LAYER_DIFFUSE) {
#if LUX_SPECULAR
    /* Appendix B fresnel_mix: the dielectric's F(wo.h), f0 from its ior. */
    const float3 h = normalize(wo + wi);
    const float c = 1.0f - lux_saturate(dot(wo, h));
    const float3 f =
        m->f0_dielectric + (m->f90_dielectric - m->f0_dielectric) * (c * c * c * c * c);
    return m->diffuse * (LUX_INV_PI * (1.0f - f)) +
           m->ms * fmax(1.0f - lux_ggx_albedo(wi.z, m->roughness), 0.0f);
#else
    return m->diffuse * LUX_INV_PI;
#endif
  }
#if LUX_SPECULAR
  if (layer == LUX_BSDF_LAYER_SPECULAR) {
    const float3 h = normalize(wo + wi);
    const float d = lux_ggx_d(h, m->alpha);
    const float g = lux_ggx_g2(wo, wi, m->alpha);
    return lux_fresnel_schlick(m->f0, m->f90, dot(wo, h)) * (d * g / (4.0f * wo.z * wi.z));
  }
#endif
  return (float3)(0.0f);
}

/* p_layer * pdf_layer(wi), solid angle; 0 below the horizon. The reflection
 * Jacobian 1 / (4 wo.h) cancels the wo.h of the visible-normal density. */
inline float lux_bsdf_pdf_layer(const LuxBsdf* m, int layer, float3 wo, float3 wi) {
  if (wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
  if (layer == LUX_BSDF_LAYER_DIFFUSE) {
#if LUX_SPECULAR
    float pdf = m->p_cosine * lux_cosine_hemisphere_pdf(wi.z);
    if (m->p_cosine < 1.0f) pdf += (1.0f - m->p_cosine) * lux_ggx_ms_pdf(m->roughness, wi.z);
    return (1.0f - m->p_specular) * pdf;
#else
    return (1.0f - m->p_specular) * lux_cosine_hemisphere_pdf(wi.z);
#endif
  }
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
    *weight = lux_fresnel_schlick(m->f0, m->f90, dot(wo, hr)) *
              (lux_ggx_g2(wo, *wi, m->alpha) / (lux_ggx_g1(wo, m->alpha) * m->p_specular));
    return LUX_BSDF_LAYER_SPECULAR;
  }
  if (m->p_cosine < 1.0f) {
    /* Layer 0 as a mixture: u_layer, rescaled to [0, 1) past p_specular,
     * picks cosine or compensation sampling, and again the table row. */
    const float v = (u_layer - m->p_specular) / (1.0f - m->p_specular);
    if (v < m->p_cosine) {
      *wi = lux_cosine_hemisphere(u);
    } else {
      const float v_row = lux_saturate((v - m->p_cosine) / (1.0f - m->p_cosine));
      *wi = lux_ggx_ms_sample(m->roughness, v_row, u);
    }
    if ((*wi).z <= 0.0f) return -1;
    *pdf = lux_bsdf_pdf_layer(m, LUX_BSDF_LAYER_DIFFUSE, wo, *wi);
    if (!(*pdf > 0.0f)) return -1;
    *weight = lux_bsdf_eval_layer(m, LUX_BSDF_LAYER_DIFFUSE, wo, *wi) * ((*wi).z / *pdf);
    return LUX_BSDF_LAYER_DIFFUSE;
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
