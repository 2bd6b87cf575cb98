// The CPU reference's own implementation of the glTF 2.0 metallic-roughness
// BRDF (glTF 2.0 specification, Appendix B "BRDF Implementation", B.3) with
// the Kulla-Conty multiple-scattering compensation (Kulla & Conty 2017,
// "Revisiting Physically Based Shading at Imageworks", "Energy
// compensation" and "Fresnel"), in double precision.
//
// Tests only, and written from the formulas, not from the kernels: nothing
// here includes kernels/ code or the generated albedo table; E(mu) is this
// file's own quadrature, per roughness.
//
// In the local shading frame (z = shading normal), wo towards the previous
// vertex, wi towards the light, h = normalize(wo + wi), alpha = roughness^2:
//   spec       = D(h) G2(wo, wi) / (4 wo.z wi.z)
//                D GGX: alpha^2 / (pi (h.z^2 (alpha^2 - 1) + 1)^2)
//                G2 Smith height-correlated (Heitz 2014, "Understanding the
//                Masking-Shadowing Function", Eq. 99): 1 / (1 + L(wo) + L(wi)),
//                L(w) = (sqrt(1 + alpha^2 tan^2 theta_w) - 1) / 2
//   F(f0, c)   = f0 + (1 - f0) (1 - c)^5 (Schlick)
//   metal      = F(base, wo.h) spec                       (conductor_fresnel)
//   dielectric = F(0.04, wo.h) spec + (1 - F(0.04, wo.h)) base / pi
//                                                          (fresnel_mix, ior 1.5)
//   f_ss       = (1 - metallic) dielectric + metallic metal
//   f_ms       = F_ms (1 - E(wo.z)) (1 - E(wi.z)) / (pi (1 - E_avg)),
//                F_ms(f0) = F_avg^2 E_avg / (1 - F_avg (1 - E_avg)),
//                F_avg = f0 + (1 - f0) / 21, mixed over metallic like B.3:
//                (1 - metallic) F_ms(0.04) + metallic F_ms(base)
//   f          = f_ss + f_ms
// with E(mu) = integral of spec cos over the hemisphere (F = 1) and
// E_avg = 2 integral E(mu) mu dmu.
#pragma once

#include <memory>
#include <vector>

#include "reference/rgb.h"

namespace luxel::reference {

// A direction in the local shading frame (z = shading normal).
struct Dir3 {
  double x = 0, y = 0, z = 0;
};

// Which BRDF the reference evaluates. Only kGltf is the engine's model; the
// others exist so a test can show the agreement check rejects them.
enum class BrdfModel {
  kGltf,            // Appendix B + Kulla-Conty compensation (above)
  kNoCompensation,  // Appendix B alone: f_ss
  // The model before Appendix B was adopted: specular F(f0, wo.h) spec with
  // f0 = mix(0.04, base, metallic), diffuse (1 - metallic) base / pi weighted
  // by 1 - F(f0, wo.z) (the normal, not the half vector), no compensation.
  kPreviousDiffuseWeight,
};

// E(mu) for one roughness: single-scattering GGX albedo with F = 1, tabulated
// at kNodes nodes uniform in sqrt(mu) by quadrature and interpolated
// linearly; E_avg is the exact integral of the interpolant, so f_ms
// reflects exactly 1 - E(wo.z) against the table.
class GgxAlbedo {
 public:
  static constexpr int kNodes = 257;

  explicit GgxAlbedo(double roughness);
  // Shared, built once per roughness value (thread-safe).
  static std::shared_ptr<const GgxAlbedo> get(double roughness);
  // E(mu) for GGX alpha by a composite Gauss-Legendre quadrature over the
  // half vector (the table's nodes): h is parameterised by the GGX
  // distribution of D(h) h.z, so the peak needs no special grid.
  static double quadrature(double mu, double alpha);

  double roughness() const { return roughness_; }
  double operator()(double mu) const;  // interpolated E(mu), mu in [0, 1]
  double average() const { return e_avg_; }

 private:
  double roughness_;
  std::vector<double> e_;  // at mu = (i / (kNodes - 1))^2
  double e_avg_ = 0;
};

// GGX terms (alpha = roughness^2).
double ggx_d(double cos_h, double alpha);
double ggx_lambda(const Dir3& w, double alpha);
double ggx_g2(const Dir3& wo, const Dir3& wi, double alpha);

// The BRDF of one material, for evaluation and sampling.
struct GgxBrdf {
  Rgb base;  // baseColorFactor.rgb
  double metallic = 0;
  double roughness = 1;
  const GgxAlbedo* albedo = nullptr;  // E for `roughness` (kGltf only)
  BrdfModel model = BrdfModel::kGltf;

  // f(wo, wi) (not times cos); 0 when either is at or below the horizon.
  Rgb eval(const Dir3& wo, const Dir3& wi) const;

  // Sampling: a one-sample mixture of the cosine hemisphere (probability
  // 1 - p_ggx()) and the GGX distribution of D(h) h.z reflected about h
  // (p_ggx()). pdf is the mixture's density over solid angle (0 below the
  // horizon); sample() may return a direction below the horizon, which
  // contributes 0. u_choice, u1, u2 uniform in [0, 1).
  double p_ggx() const { return 0.25 + 0.5 * metallic; }
  Dir3 sample(const Dir3& wo, double u_choice, double u1, double u2) const;
  double pdf(const Dir3& wo, const Dir3& wi) const;
};

}  // namespace luxel::reference
