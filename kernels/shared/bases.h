/* Spherical basis functions for directional lightmaps, evaluated in float on
 * both sides (OpenCL C 1.2 and C++20 via compat.h). Core thesis (Roughton
 * 2019) Ch. 8: spherical harmonics (§8.1), spherical Gaussians (§8.2, Eq. 8.2)
 * and the cosine-lobe Ambient Dice (§8.3, Eq. 8.3/8.4), plus diffuse
 * reconstruction from radiance-encoding coefficients (§7.4, §8.4.1).
 *
 * Units: coefficients encode RADIANCE. Every *_irradiance function returns
 * irradiance E(n) = integral over the hemisphere about n of L(w) (n.w) dw, so a
 * constant radiance L reconstructs to pi * L. Directions are unit vectors. */
#ifndef LUXEL_SHARED_BASES_H
#define LUXEL_SHARED_BASES_H

#include "shared/compat.h"

#ifdef LUX_DEVICE
#define LUX_BASES_EXP(x) exp(x)
#define LUX_BASES_SQRT(x) sqrt(x)
#else
#define LUX_BASES_EXP(x) std::exp(x)
#define LUX_BASES_SQRT(x) std::sqrt(x)
#endif

#define LUX_BASES_PI 3.14159265358979323846f

/* ---- Spherical harmonics (§8.1): real, orthonormal over the sphere (Eq. 8.1).
 * Order: l=0; l=1 (y, z, x); l=2 (xy, yz, 3z^2-1, xz, x^2-y^2), i.e. index
 * l*(l+1)+m as in Ramamoorthi & Hanrahan 2001 ("An Efficient Representation
 * for Irradiance Environment Maps"), whose constants these are. */
#define LUX_SH_L1_COUNT 4
#define LUX_SH_L2_COUNT 9

LUX_INLINE void lux_sh_eval(float x, float y, float z, int count, float* out) {
  out[0] = 0.282094792f; /* 1 / (2 sqrt(pi)) */
  if (count <= 1) return;
  out[1] = 0.488602512f * y; /* sqrt(3 / (4 pi)) */
  out[2] = 0.488602512f * z;
  out[3] = 0.488602512f * x;
  if (count <= 4) return;
  out[4] = 1.092548431f * x * y; /* sqrt(15 / (4 pi)) */
  out[5] = 1.092548431f * y * z;
  out[6] = 0.315391565f * (3.0f * z * z - 1.0f); /* sqrt(5 / (16 pi)) */
  out[7] = 1.092548431f * x * z;
  out[8] = 0.546274215f * (x * x - y * y); /* sqrt(15 / (16 pi)) */
}

/* Band l of the clamped-cosine kernel in SH (Ramamoorthi & Hanrahan 2001,
 * Eq. 8 / §7.4 of the thesis): A_0 = pi, A_1 = 2 pi / 3, A_2 = pi / 4. */
LUX_INLINE float lux_sh_cosine_band(int l) {
  return l == 0 ? LUX_BASES_PI : (l == 1 ? 2.0f * LUX_BASES_PI / 3.0f : 0.25f * LUX_BASES_PI);
}

/* E(n) = sum_lm A_l c_lm Y_lm(n): exact for signals band-limited to `count`. */
LUX_INLINE float lux_sh_diffuse_irradiance(const float* coeffs, int count, float nx, float ny,
                                           float nz) {
  float y[LUX_SH_L2_COUNT];
  lux_sh_eval(nx, ny, nz, count, y);
  float e = lux_sh_cosine_band(0) * coeffs[0] * y[0];
  for (int i = 1; i < count; ++i) e += lux_sh_cosine_band(i < 4 ? 1 : 2) * coeffs[i] * y[i];
  return e;
}

/* ---- Spherical Gaussians (§8.2): G(w; p, lambda) = exp(lambda (w.p - 1)),
 * Eq. 8.2 with unit amplitude; the amplitude is the stored coefficient. */
LUX_INLINE float lux_sg_eval(float cos_to_axis, float lambda) {
  return LUX_BASES_EXP(lambda * (cos_to_axis - 1.0f));
}

/* Integral of one lobe over the sphere: 2 pi / lambda (1 - exp(-2 lambda)). */
LUX_INLINE float lux_sg_integral(float lambda) {
  return 2.0f * LUX_BASES_PI / lambda * (1.0f - LUX_BASES_EXP(-2.0f * lambda));
}

/* Irradiance at normal n from a unit-amplitude lobe: Stephen Hill's fit of the
 * SG x clamped-cosine integral (the thesis' ref. [91], as published by
 * Pettineo, "SG Series Part 3", 2016, SGIrradianceFitted). mu_dot_n = p.n.
 * The fit is normalised by ApproximateSGIntegral = 2 pi / lambda. */
LUX_INLINE float lux_sg_diffuse_irradiance_hill(float mu_dot_n, float lambda) {
  const float c0 = 0.36f;
  const float c1 = 1.0f / (4.0f * c0);
  const float eml = LUX_BASES_EXP(-lambda);
  const float em2l = eml * eml;
  const float rl = 1.0f / lambda;
  const float scale = 1.0f + 2.0f * em2l - rl;
  const float bias = (eml - em2l) * rl - em2l;
  const float x = LUX_BASES_SQRT(1.0f - scale);
  const float x0 = c0 * mu_dot_n;
  const float x1 = c1 * x;
  const float n = x0 + x1;
  float y = mu_dot_n < 0.0f ? 0.0f : (mu_dot_n > 1.0f ? 1.0f : mu_dot_n);
  if ((x0 < 0.0f ? -x0 : x0) <= x1) y = n * n / x;
  return (scale * y + bias) * (2.0f * LUX_BASES_PI * rl);
}

/* ---- Ambient Dice cosine lobes (§8.3, Eq. 8.3 and 8.4):
 * B_i(s) = 0.7 * x^2 / 2 + 0.3 * 5 x^4 / 6 for x = v_i . s >= 0, else 0. */
LUX_INLINE float lux_ad_cosine_lobe(float cos_to_vertex) {
  const float x = cos_to_vertex > 0.0f ? cos_to_vertex : 0.0f;
  const float x2 = x * x;
  return 0.35f * x2 + 0.25f * x2 * x2;
}

/* Quadratic fit of one lobe's Lambertian response (Eq. 8.14):
 * I_i ~ integral over the hemisphere about n of B_i(s) (n.s) / pi ds, with
 * cos_lobe = v_i . n. Multiply by pi for irradiance (Eq. 8.15 gives E / pi). */
LUX_INLINE float lux_ad_diffuse_fit(float cos_lobe) {
  return 0.05981f + 0.12918f * cos_lobe + 0.07056f * cos_lobe * cos_lobe;
}

/* Lobe counts of the two Ambient Dice layouts: the icosahedron (§8.3) and the
 * nine-vertex hemisphere set (§8.3.1). The vertex directions are listed in
 * server/engine/encode/basis.cpp and in the bake manifest. */
#define LUX_AD_HEMISPHERE_COUNT 9
#define LUX_AD_SPHERE_COUNT 12

#endif /* LUXEL_SHARED_BASES_H */
