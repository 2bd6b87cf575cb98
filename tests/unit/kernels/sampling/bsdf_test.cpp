// lux_make_bsdf, lux_bsdf_sample / _eval_layer / _pdf_layer
// (kernels/shading/bsdf.h) on the device: parameters, sample consistency,
// white-furnace energy, finiteness at the extremes.
#include <cmath>
#include <random>

#include "fixture.h"

namespace luxel::sampling_test {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr float kWoAzimuth = 0.7f;
// One-sided normal quantile for the energy bounds: P(Z > 5) = 2.9e-7, so
// even a few hundred bounds stay below kFamilySignificance together.
constexpr double kZ = 5.0;

float4 wo_at(double cos_theta) {
  return to_float4(spherical_direction(cos_theta, kWoAzimuth));
}

bool finite(const float4& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) && std::isfinite(v.w);
}

using BsdfTest = SamplingTest;

TEST_F(BsdfTest, MakeBsdfFollowsGltfMetallicRoughness) {
  const std::vector<float4> materials = {{0.8f, 0.5f, 0.3f, 0.0f}, {0.8f, 0.5f, 0.3f, 1.0f},
                                         {0.8f, 0.5f, 0.3f, 0.5f}, {1.0f, 1.0f, 1.0f, 0.0f},
                                         {0.0f, 0.0f, 0.0f, 0.0f}, {0.02f, 0.02f, 0.02f, 0.0f}};
  const std::vector<float4> roughness = {{0.0f, 0, 0, 0}, {1.0f, 0, 0, 0}, {0.5f, 0, 0, 0},
                                         {0.3f, 0, 0, 0}, {0.0f, 0, 0, 0}, {0.7f, 0, 0, 0}};
  for (Build build : {Build::kSobolSpecular, Build::kRandomDiffuseOnly}) {
    const bool specular = build == Build::kSobolSpecular;
    ASSIGN_OR_FAIL(out, probe().make_bsdf(build, materials, roughness));
    for (size_t i = 0; i < materials.size(); ++i) {
      SCOPED_TRACE(testing::Message()
                   << "material " << i << (specular ? " (specular)" : " (diffuse only)"));
      const float4 base = materials[i], diffuse = out[3 * i], f0 = out[3 * i + 1],
                   ms = out[3 * i + 2];
      const float metallic = base.w, r = roughness[i].x;
      EXPECT_NEAR(diffuse.x, base.x * (1 - metallic), 1e-6);
      EXPECT_NEAR(diffuse.z, base.z * (1 - metallic), 1e-6);
      EXPECT_NEAR(f0.x, 0.04f * (1 - metallic) + base.x * metallic, 1e-6);
      EXPECT_NEAR(f0.z, 0.04f * (1 - metallic) + base.z * metallic, 1e-6);
      // alpha = roughness^2, floored so roughness 0 stays a finite lobe.
      EXPECT_GT(diffuse.w, 0.0f);
      EXPECT_LE(diffuse.w, std::max(r * r, 2e-3f));
      if (r > 0.1f) EXPECT_NEAR(diffuse.w, r * r, 1e-6);
      // The Kulla-Conty lobe: non-negative, absent without LUX_SPECULAR and
      // for smooth surfaces (nothing lost to multiple scattering).
      EXPECT_GE(std::min({ms.x, ms.y, ms.z}), 0.0f);
      if (!specular || r == 0.0f) EXPECT_EQ(ms.x + ms.y + ms.z, 0.0f);
      if (specular && r >= 0.5f && base.x > 0.0f) EXPECT_GT(ms.x, 0.0f);
      // Layer 0 samples the compensation lobe in proportion to its albedo:
      // only it for a metal, never without it.
      if (ms.x + ms.y + ms.z == 0.0f) EXPECT_EQ(ms.w, 1.0f);
      if (specular && metallic == 1.0f && r > 0.0f) EXPECT_EQ(ms.w, 0.0f);
      if (specular && metallic < 1.0f && r > 0.0f && base.x > 0.0f) {
        EXPECT_GT(ms.w, 0.5f);
        EXPECT_LT(ms.w, 1.0f);
      }
      const float p = f0.w;
      if (!specular) {
        EXPECT_EQ(p, 0.0f);
      } else if (metallic == 1.0f && r == 0.0f) {
        EXPECT_EQ(p, 1.0f) << "a smooth metal only has the specular layer";
      } else if (metallic == 1.0f) {
        EXPECT_GT(p, 0.5f) << "the compensation lobe is the smaller share";
        EXPECT_LT(p, 1.0f) << "a rough metal samples its compensation lobe too";
      } else if (base.x == 0.0f) {
        EXPECT_EQ(p, 1.0f) << "a smooth black dielectric only reflects specularly";
      } else {
        EXPECT_GE(p, 0.1f);
        EXPECT_LE(p, 0.9f);
      }
    }
  }
}

// For every valid sample: pdf == lux_bsdf_pdf_layer(layer, wi), weight ==
// f_layer(wi) cos / pdf, wi a unit direction above the horizon, and the layer
// the one u_layer selects.
TEST_F(BsdfTest, SampleReportsTheLayerPdfAndWeightFCosOverPdf) {
  const size_t n = size_t(1) << 16;
  const Material materials[] = {{{0.8f, 0.5f, 0.3f, 0.0f}, 0.5f},
                                {{0.8f, 0.5f, 0.3f, 0.5f}, 0.1f},
                                {{0.9f, 0.9f, 0.9f, 1.0f}, 0.0f},
                                {{0.2f, 0.7f, 0.4f, 0.2f}, 1.0f}};
  const auto& uniforms = probe().uniforms();
  for (Build build : {Build::kSobolSpecular, Build::kRandomDiffuseOnly})
    for (const Material& m : materials)
      for (double cz : {1.0, 0.6, 0.05}) {
        SCOPED_TRACE(testing::Message() << "roughness " << m.roughness << " metallic "
                                        << m.base_metallic.w << " wo.z " << cz);
        ASSIGN_OR_FAIL(params, probe().make_bsdf(build, {m.base_metallic},
                                                 {float4{m.roughness, float(cz), 0, 0}}));
        const float p_specular = params[1].w;
        ASSIGN_OR_FAIL(s, probe().bsdf_sample(build, m, wo_at(cz), -1.0f, n));
        size_t valid = 0;
        for (size_t i = 0; i < n; ++i) {
          const int layer = int(s.sample[i].w);
          if (layer < 0) continue;
          ++valid;
          ASSERT_EQ(layer, uniforms[i].z < p_specular ? 1 : 0) << "sample " << i;
          const Vec3 wi = to_vec3(s.sample[i]);
          ASSERT_NEAR(length(wi), 1.0, 1e-5) << "sample " << i;
          ASSERT_GT(wi.z, 0.0) << "sample " << i;
          const float pdf = s.weight[i].w;
          ASSERT_GT(pdf, 0.0f) << "sample " << i;
          ASSERT_NEAR(pdf, s.check[i].w, 1e-5 * pdf) << "sample " << i;
          const float w[3] = {s.weight[i].x, s.weight[i].y, s.weight[i].z};
          const float f_cos_over_pdf[3] = {s.check[i].x, s.check[i].y, s.check[i].z};
          for (int ch = 0; ch < 3; ++ch)
            ASSERT_NEAR(w[ch], f_cos_over_pdf[ch], 1e-4 * std::fabs(f_cos_over_pdf[ch]) + 1e-7)
                << "sample " << i << " channel " << ch;
        }
        EXPECT_GT(valid, n / 2);
      }
}

// White furnace: the directional albedo E(wo) = integral of f cos, estimated
// with the sampler (mean weight), for base colour 1. A white metal has F = 1,
// so with the Kulla-Conty compensation it reflects exactly 1 (up to the
// table's interpolation, < 3e-3 here) from smooth to rough and normal to
// grazing incidence. The dielectric follows Appendix B, which is not energy
// conserving (its diffuse (1 - F(wo.h)) ignores the light the coating
// reflects): only finiteness and greyness are checked here; its value is
// checked against an independent quadrature in bsdf_albedo_test.cpp.
TEST_F(BsdfTest, WhiteFurnaceAlbedoOfAWhiteMetalIsOne) {
  const size_t n = size_t(1) << 16;
  double worst = 0.0, least = 2.0;
  for (float metallic : {0.0f, 0.5f, 1.0f})
    for (float roughness : {0.0f, 0.05f, 0.2f, 0.5f, 1.0f})
      for (double cz : {1.0, 0.5, 0.2, 0.05, 1e-3}) {
        SCOPED_TRACE(testing::Message()
                     << "metallic " << metallic << " roughness " << roughness << " wo.z " << cz);
        const Material m{{1.0f, 1.0f, 1.0f, metallic}, roughness};
        ASSIGN_OR_FAIL(s, probe().bsdf_sample(Build::kSobolSpecular, m, wo_at(cz), -1.0f, n));
        std::vector<double> w(n);
        for (size_t i = 0; i < n; ++i) {
          ASSERT_TRUE(finite(s.weight[i])) << "sample " << i;
          // A white BSDF is grey: all channels agree.
          ASSERT_EQ(s.weight[i].x, s.weight[i].z) << "sample " << i;
          w[i] = s.weight[i].x;
        }
        const MeanEstimate e = estimate_mean(w);
        if (metallic == 1.0f) {
          EXPECT_NEAR(e.mean, 1.0, kZ * e.standard_error + 3e-3)
              << "E = " << e.mean << " +- " << e.standard_error;
          worst = std::max(worst, std::fabs(e.mean - 1.0));
        }
        if (metallic == 0.0f) {
          least = std::min(least, e.mean);
          std::printf("[ energy   ] white dielectric, roughness %.2f, wo.z %.3f: albedo %.4f\n",
                      roughness, cz, e.mean);
        }
      }
  std::printf(
      "[ energy   ] white metal: largest |E - 1| %.5f; smallest white dielectric albedo %.5f\n",
      worst, least);
}

// Without LUX_SPECULAR a white material is an exact Lambertian reflector:
// every sample weighs 1, and integrating f cos over uniformly drawn
// directions (host RNG, independent of the device warps) gives 1.
TEST_F(BsdfTest, DiffuseOnlyBuildConservesEnergyExactly) {
  const Material white{{1.0f, 1.0f, 1.0f, 0.0f}, 1.0f};
  for (double cz : {1.0, 0.5, 0.05}) {
    ASSIGN_OR_FAIL(s, probe().bsdf_sample(Build::kRandomDiffuseOnly, white, wo_at(cz), -1.0f,
                                          size_t(1) << 16));
    for (size_t i = 0; i < s.weight.size(); ++i) {
      if (s.sample[i].w < 0.0f) continue;
      ASSERT_EQ(int(s.sample[i].w), 0) << "only the diffuse layer exists";
      ASSERT_NEAR(s.weight[i].x, 1.0f, 1e-6f) << "sample " << i;
    }
  }
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<float4> dirs(size_t(1) << 16);
  for (float4& d : dirs) d = to_float4(spherical_direction(u(rng), 2.0 * kPi * u(rng)));
  ASSIGN_OR_FAIL(eval, probe().bsdf_eval(Build::kRandomDiffuseOnly, white, wo_at(0.5), dirs));
  std::vector<double> estimate(dirs.size());
  for (size_t i = 0; i < dirs.size(); ++i) {
    ASSERT_EQ(eval[2 * i + 1].x, 0.0f) << "no specular layer";
    ASSERT_EQ(eval[2 * i + 1].w, 0.0f) << "no specular layer";
    estimate[i] = eval[2 * i].x * dirs[i].z * 2.0 * kPi;
  }
  const MeanEstimate e = estimate_mean(estimate);
  EXPECT_NEAR(e.mean, 1.0, kZ * e.standard_error) << "E = " << e.mean << " +- " << e.standard_error;
}

// Two independent estimators of the albedo agree: the sampler's mean weight,
// and f cos integrated over uniform hemisphere directions from the host.
TEST_F(BsdfTest, SampledAndEvaluatedAlbedoAgree) {
  const size_t n = size_t(1) << 17;
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<float4> dirs(n);
  for (float4& d : dirs) d = to_float4(spherical_direction(u(rng), 2.0 * kPi * u(rng)));
  for (float metallic : {0.0f, 1.0f})
    for (float roughness : {0.5f, 1.0f})
      for (double cz : {0.9, 0.5, 0.1}) {
        SCOPED_TRACE(testing::Message()
                     << "metallic " << metallic << " roughness " << roughness << " wo.z " << cz);
        const Material m{{0.9f, 0.6f, 0.3f, metallic}, roughness};
        ASSIGN_OR_FAIL(s, probe().bsdf_sample(Build::kSobolSpecular, m, wo_at(cz), -1.0f, n));
        ASSIGN_OR_FAIL(eval, probe().bsdf_eval(Build::kSobolSpecular, m, wo_at(cz), dirs));
        for (int ch = 0; ch < 3; ++ch) {
          std::vector<double> sampled(n), evaluated(n);
          for (size_t i = 0; i < n; ++i) {
            const float4& w = s.weight[i];
            sampled[i] = ch == 0 ? w.x : ch == 1 ? w.y : w.z;
            const float4 &fd = eval[2 * i], &fs = eval[2 * i + 1];
            const double f = ch == 0 ? fd.x + fs.x : ch == 1 ? fd.y + fs.y : fd.z + fs.z;
            evaluated[i] = f * dirs[i].z * 2.0 * kPi;
          }
          const MeanEstimate a = estimate_mean(sampled), b = estimate_mean(evaluated);
          const double se = std::hypot(a.standard_error, b.standard_error);
          EXPECT_NEAR(a.mean, b.mean, kZ * se) << "channel " << ch;
        }
      }
}

// Roughness 0 and 1, normal and grazing incidence: weights, pdfs and
// evaluations are finite and non-negative, including at wi = wo, at the
// mirror direction and at grazing wi.
TEST_F(BsdfTest, ExtremeRoughnessAndGrazingAnglesStayFinite) {
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (float roughness : {0.0f, 1.0f})
    for (float metallic : {0.0f, 1.0f})
      for (double cz : {1.0, 0.05, 1e-3, 1e-6}) {
        SCOPED_TRACE(testing::Message()
                     << "roughness " << roughness << " metallic " << metallic << " wo.z " << cz);
        const Material m{{0.9f, 0.6f, 0.3f, metallic}, roughness};
        const float4 wo = wo_at(cz);
        ASSIGN_OR_FAIL(s,
                       probe().bsdf_sample(Build::kSobolSpecular, m, wo, -1.0f, size_t(1) << 16));
        for (size_t i = 0; i < s.sample.size(); ++i) {
          ASSERT_TRUE(finite(s.sample[i]) && finite(s.weight[i])) << "sample " << i;
          if (s.sample[i].w < 0.0f) continue;
          ASSERT_GE(std::min({s.weight[i].x, s.weight[i].y, s.weight[i].z}), 0.0f)
              << "sample " << i;
          ASSERT_GT(s.weight[i].w, 0.0f) << "sample " << i;
        }
        const Vec3 w = to_vec3(wo);
        std::vector<float4> dirs = {wo, to_float4(Vec3{-w.x, -w.y, w.z}), float4{0, 0, 1, 0},
                                    to_float4(normalize(Vec3{1, 0, 1e-6})),
                                    to_float4(normalize(Vec3{-1, 0, 1e-6}))};
        while (dirs.size() < 4096)
          dirs.push_back(to_float4(spherical_direction(u(rng), 2.0 * kPi * u(rng))));
        ASSIGN_OR_FAIL(eval, probe().bsdf_eval(Build::kSobolSpecular, m, wo, dirs));
        for (size_t i = 0; i < eval.size(); ++i) {
          ASSERT_TRUE(finite(eval[i])) << "direction " << i / 2 << " layer " << i % 2;
          ASSERT_GE(std::min({eval[i].x, eval[i].y, eval[i].z, eval[i].w}), 0.0f)
              << "direction " << i / 2;
        }
      }
}

TEST_F(BsdfTest, DirectionsBelowTheHorizonAreRejected) {
  const Material m{{0.8f, 0.5f, 0.3f, 0.5f}, 0.4f};
  const float4 below = to_float4(normalize(Vec3{0.6, 0.1, -0.8}));
  for (Build build : {Build::kSobolSpecular, Build::kRandomDiffuseOnly}) {
    ASSIGN_OR_FAIL(s, probe().bsdf_sample(build, m, below, -1.0f, 4096));
    for (size_t i = 0; i < s.sample.size(); ++i) {
      ASSERT_EQ(s.sample[i].w, -1.0f) << "sample " << i;
      ASSERT_EQ(s.weight[i].w, 0.0f) << "sample " << i;
    }
    // wo below, or wi below: both layers evaluate to 0.
    ASSIGN_OR_FAIL(e1, probe().bsdf_eval(build, m, below, {float4{0, 0, 1, 0}}));
    ASSIGN_OR_FAIL(e2, probe().bsdf_eval(build, m, wo_at(0.5), {below}));
    for (const float4& v : {e1[0], e1[1], e2[0], e2[1]}) {
      EXPECT_EQ(v.x, 0.0f);
      EXPECT_EQ(v.w, 0.0f);
    }
  }
}

}  // namespace
}  // namespace luxel::sampling_test
