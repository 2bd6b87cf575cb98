// Chi-square goodness of fit of lux_bsdf_sample (kernels/shading/bsdf.h)
// against the densities lux_bsdf_pdf_layer reports: the GGX visible-normal
// specular layer alone, the Eq. 6.2 layer mixture, and the diffuse-only build.
#include <functional>

#include "fixture.h"

namespace luxel::sampling_test {
namespace {

constexpr size_t kSamples = size_t(1) << 19;
// wo lies off the x axis so a lobe that ignored wo's azimuth would show.
constexpr double kWoAzimuth = 0.7;

float4 wo_at(double cos_theta) {
  return to_float4(spherical_direction(cos_theta, kWoAzimuth));
}

struct Params {
  double alpha, p_specular;
};

Result<Params> params_of(Probe& probe, Build build, const Material& m, float4 wo) {
  auto out = probe.make_bsdf(build, {m.base_metallic}, {float4{m.roughness, wo.z, 0, 0}});
  if (!out) return out.status();
  return Params{out.value()[0].w, out.value()[1].w};
}

// Density of the sampled directions at a node, from probe_bsdf_eval's
// (f_diffuse, pdf_diffuse), (f_specular, pdf_specular).
using Density = std::function<double(const float4& diffuse, const float4& specular)>;

struct Case {
  Build build;
  Material material;
  float4 wo;
  float u_layer_override;
  const DirectionBinning* binning;
  Density density;
  int expect_layer;  // -1: any
};

Result<Chi2Outcome> run_case(Probe& probe, const Case& c, double significance) {
  auto samples = probe.bsdf_sample(c.build, c.material, c.wo, c.u_layer_override, kSamples);
  if (!samples) return samples.status();
  std::vector<Vec3> dirs;
  dirs.reserve(kSamples);
  for (const float4& s : samples->sample) {
    const int layer = int(s.w);
    if (layer < 0) continue;
    if (c.expect_layer >= 0 && layer != c.expect_layer)
      return internal_error(
          strprintf("sampled layer %d, expected only layer %d", layer, c.expect_layer));
    dirs.push_back(to_vec3(s));
  }
  const auto nodes = c.binning->quadrature();
  std::vector<float4> node_dirs;
  node_dirs.reserve(nodes.size());
  for (const auto& n : nodes) node_dirs.push_back(to_float4(n.dir));
  auto eval = probe.bsdf_eval(c.build, c.material, c.wo, node_dirs);
  if (!eval) return eval.status();
  std::vector<double> pdf(nodes.size());
  for (size_t i = 0; i < nodes.size(); ++i)
    pdf[i] = c.density(eval.value()[2 * i], eval.value()[2 * i + 1]);
  return directional_chi2(*c.binning, nodes, pdf, dirs, kSamples, significance);
}

using BsdfChi2Test = SamplingTest;

// u_layer = 0 always picks the specular layer, whose density is then
// pdf_specular / p_specular. Cells crowd around the mirror direction so the
// narrowest lobes (roughness 0.05, alpha 0.0025) span many cells.
TEST_F(BsdfChi2Test, SpecularLayerMatchesItsDensity) {
  const float roughnesses[] = {0.05f, 0.1f, 0.3f, 0.6f, 1.0f};
  const double wo_cos[] = {1.0, 0.5, 0.05};
  const double significance = kFamilySignificance / (std::size(roughnesses) * std::size(wo_cos));
  for (float roughness : roughnesses)
    for (double cz : wo_cos) {
      const Material m{{0.8f, 0.5f, 0.3f, 0.5f}, roughness};
      ASSIGN_OR_FAIL(params, params_of(probe(), Build::kSobolSpecular, m, wo_at(cz)));
      ASSERT_GT(params.p_specular, 0.0);
      const auto binning =
          SphericalBinning::around_mirror(64, 64, to_vec3(wo_at(cz)), params.alpha);
      const double p = params.p_specular;
      const Case c{Build::kSobolSpecular,
                   m,
                   wo_at(cz),
                   0.0f,
                   &binning,
                   [p](const float4&, const float4& s) { return s.w / p; },
                   1};
      ASSIGN_OR_FAIL(chi2, run_case(probe(), c, significance));
      EXPECT_TRUE(chi2.passed) << "roughness " << roughness << ", wo.z " << cz << ": "
                               << chi2.detail;
    }
}

// The Eq. 6.2 mixture: layer chosen with probability p_specular, so the
// sampled density is the sum of both lux_bsdf_pdf_layer values.
TEST_F(BsdfChi2Test, LayerMixtureMatchesTheSumOfLayerDensities) {
  const float roughnesses[] = {0.05f, 0.3f, 0.6f, 1.0f};
  const double wo_cos[] = {0.9, 0.4, 0.05};
  const double significance = kFamilySignificance / (std::size(roughnesses) * std::size(wo_cos));
  for (float roughness : roughnesses)
    for (double cz : wo_cos) {
      const Material m{{0.8f, 0.5f, 0.3f, 0.5f}, roughness};
      ASSIGN_OR_FAIL(params, params_of(probe(), Build::kSobolSpecular, m, wo_at(cz)));
      ASSERT_GT(params.p_specular, 0.2) << "both layers are sampled often";
      ASSERT_LT(params.p_specular, 0.8);
      const auto binning =
          SphericalBinning::around_mirror(64, 64, to_vec3(wo_at(cz)), params.alpha);
      const Case c{Build::kSobolSpecular,
                   m,
                   wo_at(cz),
                   -1.0f,
                   &binning,
                   [](const float4& d, const float4& s) { return double(d.w) + s.w; },
                   -1};
      ASSIGN_OR_FAIL(chi2, run_case(probe(), c, significance));
      EXPECT_TRUE(chi2.passed) << "roughness " << roughness << ", wo.z " << cz << ": "
                               << chi2.detail;
    }
}

// A metal's layer 0 is the Kulla-Conty compensation lobe alone, sampled from
// its tabulated distribution (lux_ggx_ms_sample): u_layer just below 1
// forces it, and the density is then pdf_diffuse / (1 - p_specular). Cells
// uniform in cos theta and phi; the lobe hugs the horizon for low roughness.
// A fixed u_layer also fixes the choice between the two table rows around
// the roughness (it reuses u_layer), so the roughnesses sit on table rows
// (j / 31), where that choice is moot; the layer mixture test covers
// roughnesses between rows with random u_layer.
TEST_F(BsdfChi2Test, CompensationLobeMatchesItsDensity) {
  const float roughnesses[] = {6.0f / 31.0f, 15.0f / 31.0f, 1.0f};
  const double wo_cos[] = {0.9, 0.3};
  const double significance = kFamilySignificance / (std::size(roughnesses) * std::size(wo_cos));
  for (float roughness : roughnesses)
    for (double cz : wo_cos) {
      const Material m{{0.95f, 0.64f, 0.54f, 1.0f}, roughness};
      ASSIGN_OR_FAIL(params, params_of(probe(), Build::kSobolSpecular, m, wo_at(cz)));
      ASSERT_LT(params.p_specular, 0.9999) << "the compensation lobe is sampled";
      const auto binning = SphericalBinning::uniform(64, 32, 0.0, 1.0);
      const double q = 1.0 - params.p_specular;
      const Case c{Build::kSobolSpecular,
                   m,
                   wo_at(cz),
                   0.99999f,
                   &binning,
                   [q](const float4& d, const float4&) { return double(d.w) / q; },
                   0};
      ASSIGN_OR_FAIL(chi2, run_case(probe(), c, significance));
      EXPECT_TRUE(chi2.passed) << "roughness " << roughness << ", wo.z " << cz << ": "
                               << chi2.detail;
    }
}

TEST_F(BsdfChi2Test, DiffuseOnlyBuildSamplesTheCosineLobe) {
  const Material m{{0.8f, 0.5f, 0.3f, 0.5f}, 0.4f};
  const auto binning = SphericalBinning::uniform(32, 64, 0.0, 1.0);
  const Case c{Build::kRandomDiffuseOnly,
               m,
               wo_at(0.5),
               -1.0f,
               &binning,
               [](const float4& d, const float4&) { return double(d.w); },
               0};
  ASSIGN_OR_FAIL(chi2, run_case(probe(), c, kFamilySignificance));
  EXPECT_TRUE(chi2.passed) << chi2.detail;
}

}  // namespace
}  // namespace luxel::sampling_test
