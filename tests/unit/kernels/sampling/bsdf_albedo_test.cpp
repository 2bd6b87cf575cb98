// Directional albedo of the device BSDF (kernels/shading/bsdf.h: glTF 2.0
// Appendix B plus the Kulla-Conty compensation) against an independent
// numerical quadrature of the same model written here, in double precision,
// without the kernel headers or the generated table. The device side is
// the renderer's own estimator: the mean sampling weight f cos / pdf of
// lux_bsdf_sample over 2^20 samples.
//
// The model, as the glTF 2.0 specification's Appendix B (B.3) states it:
//   metal      = Schlick(base, V.H) D G2 / (4 N.V N.L)
//   dielectric = mix(base / pi, D G2 / (4 N.V N.L), Schlick(f0, V.H)), f0 0.04
//                at the default ior 1.5 (KHR_materials_ior changes it)
//   f          = mix(dielectric, metal, metallic),  alpha = roughness^2
// plus the Kulla & Conty 2017 lobe ("Revisiting Physically Based Shading at
// Imageworks"), whose albedo is F_ms (1 - E(N.V)) by construction, with
// E(mu) the F = 1 single-scattering albedo, E_avg = 2 int E mu dmu,
// F_avg = f0 + (1 - f0) / 21 and F_ms = F_avg^2 E_avg / (1 - F_avg (1 - E_avg)).
#include <cmath>

#include "fixture.h"

namespace luxel::sampling_test {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kZ = 5.0;
// The device interpolates E(mu, roughness) bilinearly in a 32 x 32 table;
// against exact quadrature that costs up to ~1e-3 of albedo (measured
// largest gap 6e-4 over these cases).
constexpr double kTableTolerance = 2e-3;

struct Albedo {
  double rgb[3] = {0, 0, 0};
};

double schlick(double f0, double c, double f90 = 1.0) {
  return f0 + (f90 - f0) * std::pow(1.0 - std::clamp(c, 0.0, 1.0), 5.0);
}

// Smith Lambda for GGX (Heitz 2014, Eq. 72).
double lambda(const Vec3& w, double alpha) {
  const double t2 = (w.x * w.x + w.y * w.y) / (w.z * w.z);
  return 0.5 * (std::sqrt(1.0 + alpha * alpha * t2) - 1.0);
}

// int F(f0_c, V.H) D G2 / (4 N.V N.L) N.L dL for the three f0 channels, in
// half-vector space: dL = 4 V.H dH, and the grid is midpoint in
// (u, v) with tan^2 theta_h = alpha^2 u / (1 - u), phi = 2 pi v, for which
// D(h) cos theta_h dH = du dv (the GGX cumulative distribution).
Albedo specular_albedo(const Vec3& v, double alpha, const double f0[3], int nu, int nv,
                       const double* f90 = nullptr) {
  Albedo a;
  const double lv = lambda(v, alpha);
  for (int i = 0; i < nu; ++i) {
    const double u = (i + 0.5) / nu;
    const double t2 = alpha * alpha * u / (1.0 - u);
    const double ch = 1.0 / std::sqrt(1.0 + t2), sh = std::sqrt(t2) * ch;
    for (int j = 0; j < nv; ++j) {
      const double phi = 2.0 * kPi * (j + 0.5) / nv;
      const Vec3 h{sh * std::cos(phi), sh * std::sin(phi), ch};
      const double vh = dot(v, h);
      if (vh <= 0.0) continue;
      const Vec3 l{2 * vh * h.x - v.x, 2 * vh * h.y - v.y, 2 * vh * h.z - v.z};
      if (l.z <= 0.0) continue;
      const double g2 = 1.0 / (1.0 + lv + lambda(l, alpha));
      const double w = g2 * vh / (v.z * ch);
      for (int c = 0; c < 3; ++c) a.rgb[c] += schlick(f0[c], vh, f90 ? f90[c] : 1.0) * w;
    }
  }
  for (double& x : a.rgb) x /= double(nu) * nv;
  return a;
}

// int (1 - Schlick(f0, V.H)) / pi N.L dL, midpoint in the cosine-weighted
// parametrization N.L = sqrt(u), phi = 2 pi v (N.L / pi dL = du dv).
double diffuse_transmission(const Vec3& v, double f0, int n, double f90 = 1.0) {
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    const double z = std::sqrt((i + 0.5) / n), r = std::sqrt(1.0 - z * z);
    for (int j = 0; j < n; ++j) {
      const double phi = 2.0 * kPi * (j + 0.5) / n;
      const Vec3 h = normalize(Vec3{v.x + r * std::cos(phi), v.y + r * std::sin(phi), v.z + z});
      sum += 1.0 - schlick(f0, dot(v, h), f90);
    }
  }
  return sum / (double(n) * n);
}

double white_albedo(double mu, double alpha, int nu, int nv) {
  const double one[3] = {1, 1, 1};
  return specular_albedo(spherical_direction(mu, 0.0), alpha, one, nu, nv).rgb[0];
}

// E_avg = 2 int_0^1 E(mu) mu dmu, Gauss-Legendre on mu^2 (midpoint in
// mu^2 = s: 2 mu dmu = ds).
double average_albedo(double alpha) {
  const int n = 128;
  double sum = 0.0;
  for (int i = 0; i < n; ++i) sum += white_albedo(std::sqrt((i + 0.5) / n), alpha, 256, 128);
  return sum / n;
}

double kulla_conty_fms(double f0, double e_avg, double f90 = 1.0) {
  const double f_avg = f0 + (f90 - f0) / 21.0;
  return f_avg * f_avg * e_avg / (1.0 - f_avg * (1.0 - e_avg));
}

struct Expected {
  Albedo single, total;  // Appendix B alone; with the compensation lobe
  // The model before Appendix B: diffuse weighted by 1 - F(f0, N.V), no
  // compensation. Used as an injected error the test must reject.
  Albedo old;
};

Expected quadrature(const Material& m, double cz, double e_avg) {
  const double base[3] = {m.base_metallic.x, m.base_metallic.y, m.base_metallic.z};
  const double metallic = m.base_metallic.w;
  const double alpha = std::max(double(m.roughness) * m.roughness, 1e-3);
  const Vec3 v = spherical_direction(cz, 0.7);
  // KHR_materials_specular: the dielectric's f0 per channel and its f90.
  const bool spec_ext = m.specular.w > 0;
  const double f0_dc[3] = {spec_ext ? m.specular.x : m.dielectric_f0,
                           spec_ext ? m.specular.y : m.dielectric_f0,
                           spec_ext ? m.specular.z : m.dielectric_f0};
  const double f90_d = spec_ext ? m.specular.w : 1.0;
  double f0[3], f90[3];
  for (int c = 0; c < 3; ++c) {
    f0[c] = f0_dc[c] * (1 - metallic) + base[c] * metallic;
    f90[c] = f90_d * (1 - metallic) + metallic;
  }
  const Albedo spec = specular_albedo(v, alpha, f0, 2048, 1024, f90);
  const double e_o = white_albedo(cz, alpha, 2048, 1024);
  Expected e;
  for (int c = 0; c < 3; ++c) {
    const double t = diffuse_transmission(v, f0_dc[c], 512, f90_d);
    e.single.rgb[c] = spec.rgb[c] + base[c] * (1 - metallic) * t;
    const double fms = (1 - metallic) * kulla_conty_fms(f0_dc[c], e_avg, f90_d) +
                       metallic * kulla_conty_fms(base[c], e_avg);
    e.total.rgb[c] = e.single.rgb[c] + fms * (1.0 - e_o);
    e.old.rgb[c] = spec.rgb[c] + base[c] * (1 - metallic) * (1.0 - schlick(f0[c], cz));
  }
  return e;
}

using BsdfAlbedoTest = SamplingTest;

TEST_F(BsdfAlbedoTest, SampledAlbedoMatchesIndependentQuadrature) {
  const size_t n = Probe::kMaxSamples;
  const Material materials[] = {
      {{0.8f, 0.5f, 0.3f, 0.0f}, 0.2f},
      {{0.8f, 0.5f, 0.3f, 0.0f}, 0.5f},
      {{1.0f, 1.0f, 1.0f, 0.0f}, 0.5f},
      {{0.1f, 0.1f, 0.1f, 0.0f}, 0.8f},
      {{1.0f, 1.0f, 1.0f, 0.0f}, 1.0f},
      {{0.95f, 0.64f, 0.54f, 1.0f}, 0.2f},
      {{0.95f, 0.64f, 0.54f, 1.0f}, 0.5f},
      {{1.0f, 1.0f, 1.0f, 1.0f}, 1.0f},
      {{0.9f, 0.6f, 0.3f, 0.5f}, 0.6f},
      // KHR_materials_ior: ior 2.0 (f0 1/9) and 1.33 (f0 0.0201).
      {{0.8f, 0.5f, 0.3f, 0.0f}, 0.5f, 1.0f / 9.0f},
      {{0.3f, 0.6f, 0.9f, 0.0f}, 0.3f, 0.0201f},
      // KHR_materials_specular: specular 0.6, specularColor
      // (2, 0.5, 1) at ior 1.5: f0 = min(0.04 c, 1) 0.6, f90 0.6;
      // and specular 1 with a colour that saturates f0 (ior 3).
      {{0.8f, 0.5f, 0.3f, 0.0f}, 0.3f, 0.04f, {0.048f, 0.012f, 0.024f, 0.6f}},
      {{0.2f, 0.2f, 0.2f, 0.0f}, 0.4f, 0.25f, {1.0f, 0.25f, 0.05f, 1.0f}}};
  double worst_gap = 0.0, worst_uncompensated = 0.0;
  int rejected_old = 0, cases = 0;
  for (const Material& m : materials) {
    const double e_avg = average_albedo(std::max(double(m.roughness) * m.roughness, 1e-3));
    for (double cz : {0.9, 0.4, 0.1}) {
      SCOPED_TRACE(testing::Message()
                   << "base (" << m.base_metallic.x << ", " << m.base_metallic.y << ", "
                   << m.base_metallic.z << ") metallic " << m.base_metallic.w << " roughness "
                   << m.roughness << " wo.z " << cz);
      ASSIGN_OR_FAIL(s, probe().bsdf_sample(Build::kSobolSpecular, m,
                                            to_float4(spherical_direction(cz, 0.7)), -1.0f, n));
      const Expected e = quadrature(m, cz, e_avg);
      // A material with its own ior (or specular) must not pass as the default one.
      const bool own_ior = m.dielectric_f0 != 0.04f || m.specular.w > 0;
      const Expected e_default_ior =
          own_ior ? quadrature(Material{m.base_metallic, m.roughness}, cz, e_avg) : e;
      bool default_ior_rejected = false;
      bool old_rejected = false;
      for (int c = 0; c < 3; ++c) {
        std::vector<double> w(n);
        for (size_t i = 0; i < n; ++i) {
          const float4& x = s.weight[i];
          w[i] = c == 0 ? x.x : c == 1 ? x.y : x.z;
        }
        const MeanEstimate est = estimate_mean(w);
        EXPECT_NEAR(est.mean, e.total.rgb[c], kZ * est.standard_error + kTableTolerance)
            << "channel " << c << ": sampled " << est.mean << " +- " << est.standard_error
            << ", quadrature " << e.total.rgb[c] << " (Appendix B alone " << e.single.rgb[c] << ")";
        worst_gap = std::max(worst_gap, std::fabs(est.mean - e.total.rgb[c]));
        // The same bound must reject the previous model's weighting.
        if (std::fabs(est.mean - e.old.rgb[c]) > kZ * est.standard_error + kTableTolerance)
          old_rejected = true;
        worst_uncompensated = std::max(worst_uncompensated, e.total.rgb[c] - e.single.rgb[c]);
        if (std::fabs(est.mean - e_default_ior.total.rgb[c]) >
            kZ * est.standard_error + kTableTolerance)
          default_ior_rejected = true;
      }
      if (own_ior) EXPECT_TRUE(default_ior_rejected) << "the ior makes no difference";
      // At wo.z 0.1 both changes show for every material: the (1 - F(N.V))
      // diffuse weight for dielectrics, the missing compensation for metals.
      if (cz < 0.2) EXPECT_TRUE(old_rejected) << "the previous model would pass";
      rejected_old += old_rejected;
      ++cases;
    }
  }
  std::printf(
      "[ albedo   ] largest |sampled - quadrature| %.5f; largest compensation share %.4f; "
      "previous model rejected in %d of %d cases\n",
      worst_gap, worst_uncompensated, rejected_old, cases);
}

}  // namespace
}  // namespace luxel::sampling_test
