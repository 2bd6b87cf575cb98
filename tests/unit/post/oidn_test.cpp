// Open Image Denoise's RTLightmap filter (post/oidn.h) in real bakes against
// closed forms, with the real library (deploy/install-deps.sh installs it;
// without it these cases skip and say so):
//   (a) noise: at 4 and 16 spp the denoised RMSE against the closed form is
//       below the raw RMSE and the denoised mean stays unbiased; every texel
//       finite and non-negative;
//   (b) leaks: a dark chart beside a 20x brighter one in the atlas keeps its
//       raw mean near the border (within a confidence bound of its noise),
//       in the bake and for the filter without the blend; the same check
//       FAILS for the injected error, the filter without the blend over the
//       whole page at once (charts only dilated into their padding);
//   (c) a converged input (zero variance) comes out unchanged; the same
//       input gives the same bits;
//   (d) missing library: run once more by ctest with LUXEL_OIDN_LIBRARY at a
//       file that does not exist (oidn_missing_test): `denoise = oidn` bakes
//       with the a-trous filter and the manifest's denoise object says why;
//       `denoise = auto` (the default) leaves the map raw and says why;
//   (e) SH lightmaps (the filter's directional mode): at 16 spp the denoised
//       sh1 coefficients are closer to their closed forms (L0 from the
//       emitter's solid angle, L1 from its vector form factor) than the raw
//       ones, and unbiased; scaling the denoised L1 bands by 1.5 (the
//       injected error) breaks the same bound;
//   (f) `denoise = auto` with the library present is OIDN.
#include "post/oidn.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>

#include "bake/bake.h"
#include "post/denoise.h"
#include "support/device_context.h"
#include "unit/post/lit_quads.h"

namespace luxel {
namespace {

using testing::errors;
using testing::Errors;
using testing::Expected;
using testing::expected_irradiance;
using testing::two_charts;
using testing::TwoCharts;

bool missing_library_run() {
  const char* e = std::getenv("LUXEL_OIDN_LIBRARY");
  return e && std::string(e).find("nonexistent") != std::string::npos;
}

class OidnTest : public testing::DeviceTest<> {
 protected:
  void SetUp() override {
    if (missing_library_run()) GTEST_SKIP() << "the missing-library run tests only that";
    auto lib = pipeline::load_oidn();
    if (!lib)
      GTEST_SKIP() << "Open Image Denoise not found (deploy/install-deps.sh installs it): "
                   << lib.status().message();
  }
  static pipeline::BakeSettings settings(int resolution, uint32_t spp) {
    pipeline::BakeSettings s;
    s.atlas.resolution = resolution;
    s.samples_per_texel = spp;
    s.max_bounces = 0;  // direct light: the closed form is exact
    s.paths_per_iteration = 1u << 16;
    s.seed = 11;
    s.denoise = pipeline::Denoise::kOidn;
    return s;
  }
};

void expect_finite_non_negative(const std::vector<float>& rgba) {
  size_t bad = 0;
  for (float v : rgba) bad += !(std::isfinite(v) && v >= 0.0f);
  EXPECT_EQ(bad, 0u) << "every texel finite and non-negative";
}

// (a) One plane under a small emitter (peaked irradiance), as denoise_test's
// case (a).
TEST_F(OidnTest, LowersErrorAgainstClosedFormWithoutBias) {
  TwoCharts t = two_charts(1.0f, 1.0f, 0.5f);
  t.scene.meshes.resize(2);
  t.scene.instances.resize(2);
  for (uint32_t spp : {4u, 16u}) {
    auto r = pipeline::bake(t.scene, settings(64, spp), *ctx_);
    ASSERT_TRUE(r) << r.status().to_string();
    const pipeline::BakeResult& b = r.value();
    const auto j = nlohmann::json::parse(b.denoise_json);
    ASSERT_EQ(j["method"], "oidn") << b.denoise_json;
    EXPECT_GT(j["seconds_per_megatexel"].get<double>(), 0.0);
    ASSERT_EQ(b.irradiance_denoised.size(), b.irradiance.size());
    expect_finite_non_negative(b.irradiance_denoised);
    auto info = atlas::build_sample_info(t.scene, b.atlas);
    ASSERT_TRUE(info);
    const Expected ex = expected_irradiance(t, b.atlas, info.value(), 1);
    auto all = [](uint32_t) { return true; };
    const Errors raw = errors(b.irradiance, ex, all);
    const Errors dn = errors(b.irradiance_denoised, ex, all);
    std::printf(
        "  %u spp: %zu texels, RMSE raw %.4f oidn %.4f, mean ratio raw %.5f oidn %.5f, "
        "%.3f s/Mtexel\n",
        spp, raw.texels, raw.rmse, dn.rmse, raw.mean_ratio, dn.mean_ratio,
        j["seconds_per_megatexel"].get<double>());
    ASSERT_GT(raw.texels, 1500u);
    EXPECT_LT(dn.rmse, 0.7 * raw.rmse);
    EXPECT_NEAR(dn.mean_ratio / raw.mean_ratio, 1.0, 0.02);
    EXPECT_NEAR(dn.mean_ratio, 1.0, 0.03);
  }
}

// (b) Chart 0 dark, chart 1 20x brighter, side by side in the atlas (border
// at u = 0.5), far apart in the world. Over chart 0's texels within 4 texel
// columns of the border, the mean of the denoised map must stay within 4
// standard errors of the raw mean (the standard error of that mean from the
// texels' own variances). The injected error, the page filtered at once,
// must break the same bound.
TEST_F(OidnTest, DoesNotLeakAcrossCharts) {
  TwoCharts t = two_charts(20.0f, 8.0f, 1.0f);
  const int res = 64;
  auto r = pipeline::bake(t.scene, settings(res, 16), *ctx_);
  ASSERT_TRUE(r) << r.status().to_string();
  const pipeline::BakeResult& b = r.value();
  ASSERT_EQ(nlohmann::json::parse(b.denoise_json)["method"], "oidn");
  expect_finite_non_negative(b.irradiance_denoised);
  auto info = atlas::build_sample_info(t.scene, b.atlas);
  ASSERT_TRUE(info);
  const Expected ex = expected_irradiance(t, b.atlas, info.value(), 2);
  auto dark_near_border = [&](uint32_t texel) {
    const int x = int(texel % uint32_t(res));
    return ex.quad[texel] == 0 && x >= res / 2 - 4;
  };
  // Mean of channel 1 over the band; the variance of the raw mean.
  auto band_mean = [&](const std::vector<float>& rgba) {
    double s = 0;
    size_t n = 0;
    for (uint32_t i = 0; i < ex.e.size(); ++i)
      if (!std::isnan(ex.e[i]) && dark_near_border(i)) s += rgba[size_t(i) * 4 + 1], ++n;
    return s / double(std::max<size_t>(n, 1));
  };
  double var_sum = 0;
  size_t n = 0;
  for (uint32_t i = 0; i < ex.e.size(); ++i)
    if (!std::isnan(ex.e[i]) && dark_near_border(i)) var_sum += b.denoise_variance[i], ++n;
  ASSERT_GT(n, 100u);
  const double se = std::sqrt(var_sum) / double(n);
  const double raw = band_mean(b.irradiance), dn = band_mean(b.irradiance_denoised);

  // The filter alone (no blend: the blend bounds any change by one standard
  // error per texel and would hide a leak), per chart and, the injected
  // error, per page.
  pipeline::OidnDenoiser d(*pipeline::load_oidn().value(),
                           pipeline::build_denoise_guides(t.scene, b.atlas, info.value()),
                           b.atlas.pages);
  pipeline::OidnParams chart;
  chart.blend = pipeline::OidnBlend::kNone;
  pipeline::OidnParams page = chart;
  page.whole_pages = true;
  auto alone = d.run(b.irradiance, b.denoise_variance, chart);
  auto mixed = d.run(b.irradiance, b.denoise_variance, page);
  ASSERT_TRUE(alone && mixed);
  const double filtered = band_mean(alone.value()), bad = band_mean(mixed.value());
  const Errors e_raw = errors(b.irradiance, ex, dark_near_border);
  std::printf(
      "  dark chart by the border (%zu texels): mean raw %.4f (closed form %.4f, standard "
      "error %.4f); bake (per chart, blended) %+.2f SE; unblended: per chart %+.2f SE, whole "
      "page %+.2f SE\n",
      n, raw, raw / e_raw.mean_ratio, se, (dn - raw) / se, (filtered - raw) / se, (bad - raw) / se);
  EXPECT_LT(std::abs(dn - raw), 4 * se) << "chart 1's light leaks into chart 0 (bake)";
  EXPECT_LT(std::abs(filtered - raw), 4 * se) << "chart 1's light leaks into chart 0 (filter)";
  EXPECT_GT(std::abs(bad - raw), 4 * se) << "filtering the page at once must be detected";
}

// (c) Zero variance (the limit of a converged bake): the blend keeps every
// texel's raw value, bit for bit.
TEST_F(OidnTest, ConvergedInputUnchanged) {
  TwoCharts t = two_charts(3.0f, 1.0f, 0.5f);
  auto r = pipeline::bake(t.scene, settings(32, 4), *ctx_);
  ASSERT_TRUE(r) << r.status().to_string();
  const pipeline::BakeResult& b = r.value();
  auto info = atlas::build_sample_info(t.scene, b.atlas);
  ASSERT_TRUE(info);
  pipeline::OidnDenoiser d(*pipeline::load_oidn().value(),
                           pipeline::build_denoise_guides(t.scene, b.atlas, info.value()),
                           b.atlas.pages);
  auto out = d.run(b.irradiance, std::vector<float>(b.denoise_variance.size(), 0.0f), {});
  ASSERT_TRUE(out) << out.status().to_string();
  EXPECT_EQ(out.value(), b.irradiance);
  // Without the blend the filter does change the map (the check is not empty).
  pipeline::OidnParams off;
  off.blend = pipeline::OidnBlend::kNone;
  auto free = d.run(b.irradiance, b.denoise_variance, off);
  ASSERT_TRUE(free);
  EXPECT_NE(free.value(), b.irradiance);
  // Like the bake, the same input gives the same bits (OIDN's CPU device).
  auto again = d.run(b.irradiance, b.denoise_variance, off);
  ASSERT_TRUE(again);
  EXPECT_EQ(again.value(), free.value());
}

// Solid angle of the triangle (a, b, c) seen from the origin (Van Oosterom
// and Strackee 1983): tan(omega / 2) = |a.(b x c)| / (|a||b||c| + (a.b)|c|
// + (a.c)|b| + (b.c)|a|).
double triangle_solid_angle(Vec3 a, Vec3 b, Vec3 c) {
  const double la = length(a), lb = length(b), lc = length(c);
  const double num = std::fabs(double(dot(a, cross(b, c))));
  const double den =
      la * lb * lc + double(dot(a, b)) * lc + double(dot(a, c)) * lb + double(dot(b, c)) * la;
  return 2.0 * std::atan2(num, den);
}

// sh1 radiance coefficients (kernels/shared/bases.h order: Y00, Y1-1 ~ y,
// Y10 ~ z, Y11 ~ x; world directions, bake/encodings.h) of the light
// from quad q's emitter at plane point x: c0 = Y00 L omega and
// c1 = 0.4886 L Phi, with Phi = integral of w over the emitter's solid angle,
// the vector form factor 1/2 sum theta_i unit(r_i x r_i+1) (Arvo 1995,
// Eq. 6, before the dot product with the normal).
std::array<double, 4> sh1_closed_form(const testing::LitQuad& q, Vec3 x) {
  Vec3 r[4];
  for (int i = 0; i < 4; ++i) r[i] = q.emitter[i] - x;
  const double omega =
      triangle_solid_angle(r[0], r[1], r[2]) + triangle_solid_angle(r[0], r[2], r[3]);
  Vec3 phi{0, 0, 0};
  for (int i = 0; i < 4; ++i) {
    const Vec3 a = normalize(r[i]), b = normalize(r[(i + 1) % 4]);
    const float theta = std::acos(std::clamp(dot(a, b), -1.0f, 1.0f));
    phi = phi + normalize(cross(a, b)) * (0.5f * theta);
  }
  const Vec3 centre = (r[0] + r[1] + r[2] + r[3]) * 0.25f;
  if (dot(phi, centre) < 0) phi = phi * -1.0f;
  const double k = 0.488602512 * q.le;
  return {0.282094792 * q.le * omega, k * phi.y, k * phi.z, k * phi.x};
}

// (e) One plane under a 1 x 1 emitter, sh1, 16 spp: per coefficient, RMSE
// against the closed form averaged over each texel's sample points.
TEST_F(OidnTest, ShBandsCloserToClosedFormInDirectionalMode) {
  TwoCharts t = two_charts(1.0f, 1.0f, 0.5f);
  t.scene.meshes.resize(2);
  t.scene.instances.resize(2);
  pipeline::BakeSettings st = settings(64, 16);
  st.encodings.names = {"sh1"};
  auto r = pipeline::bake(t.scene, st, *ctx_);
  ASSERT_TRUE(r) << r.status().to_string();
  const pipeline::BakeResult& b = r.value();
  ASSERT_EQ(b.encodings.size(), 1u);
  const pipeline::EncodedLightmap& e = b.encodings[0];
  ASSERT_EQ(e.count, 4);
  ASSERT_EQ(e.coefficients_denoised.size(), e.coefficients.size()) << b.denoise_json;
  EXPECT_NE(nlohmann::json::parse(b.denoise_json)["directional"].get<std::string>().find("sh1"),
            std::string::npos);
  auto info = atlas::build_sample_info(t.scene, b.atlas);
  ASSERT_TRUE(info);
  const atlas::SampleInfo& si = info.value();
  // The closed form per texel (green channel), over its sample points.
  std::vector<std::array<double, 4>> ref(b.irradiance.size() / 4, {NAN, NAN, NAN, NAN});
  for (uint32_t texel : si.covered_texels) {
    const uint32_t valid = cl::lux_sample_info_count(si.words.data(), si.offsets[texel]);
    std::array<double, 4> sum{0, 0, 0, 0};
    bool ok = true;
    for (uint32_t k = 0; k < valid && ok; ++k) {
      const atlas::SamplePoint sp = atlas::sample_point(si, texel, k);
      ok = sp.instance == 0;  // plane 0 only
      const testing::LitQuad& q = t.q[0];
      const double u = sp.x / b.atlas.width, v = sp.y / b.atlas.height;
      const Vec3 x{float(q.x0 + 2 * (v - q.v0) / (q.v1 - q.v0)), 0,
                   float(-1 + 2 * (u - q.u0) / (q.u1 - q.u0))};
      const auto c = sh1_closed_form(q, x);
      for (int i = 0; i < 4; ++i) sum[i] += c[i];
    }
    if (!ok || valid == 0) continue;
    for (int i = 0; i < 4; ++i) ref[texel][i] = sum[i] / valid;
  }
  // RMSE of coefficient i (green channel) against ref, and its bias: the
  // mean difference over the RMS of ref (the bands along the plane average
  // to 0 by symmetry, so a ratio of means would say nothing).
  struct Cmp {
    double rmse, bias;
    size_t n;
  };
  auto compare = [&](const std::vector<float>& c, int i, double scale_bands) {
    double sq = 0, diff = 0, ref_sq = 0;
    size_t n = 0;
    for (size_t t = 0; t < ref.size(); ++t) {
      if (std::isnan(ref[t][i])) continue;
      const double v = c[t * 12 + size_t(i) * 3 + 1] * (i > 0 ? scale_bands : 1.0);
      sq += (v - ref[t][i]) * (v - ref[t][i]);
      diff += v - ref[t][i];
      ref_sq += ref[t][i] * ref[t][i];
      ++n;
    }
    const double m = double(std::max<size_t>(n, 1));
    return Cmp{std::sqrt(sq / m), diff / m / std::sqrt(ref_sq / m), n};
  };
  for (int i = 0; i < 4; ++i) {  // L0; y (the normal); z and x (along the plane)
    const Cmp raw = compare(e.coefficients, i, 1.0);
    const Cmp dn = compare(e.coefficients_denoised, i, 1.0);
    const Cmp injected = compare(e.coefficients_denoised, i, 1.5);
    std::printf(
        "  sh1 c%d: %zu texels, RMSE raw %.4f oidn %.4f (bands x1.5: %.4f), bias raw "
        "%+.4f oidn %+.4f (x1.5: %+.4f)\n",
        i, raw.n, raw.rmse, dn.rmse, injected.rmse, raw.bias, dn.bias, injected.bias);
    ASSERT_GT(raw.n, 1500u);
    EXPECT_LT(std::fabs(raw.bias), 0.03) << "the raw bake itself must match the closed form";
    EXPECT_LT(dn.rmse, 0.8 * raw.rmse) << "coefficient " << i;
    EXPECT_LT(std::fabs(dn.bias), 0.03) << "coefficient " << i;
    if (i > 0)
      EXPECT_FALSE(injected.rmse < 0.8 * raw.rmse && std::fabs(injected.bias) < 0.03)
          << "the injected error must fail the same checks";
  }
  for (float v : e.coefficients_denoised) ASSERT_TRUE(std::isfinite(v));
}

// (f) auto picks OIDN when it loads.
TEST_F(OidnTest, AutoIsOidnWhenTheLibraryLoads) {
  TwoCharts t = two_charts(1.0f, 1.0f, 0.5f);
  pipeline::BakeSettings st = settings(32, 4);
  st.denoise = pipeline::Denoise::kAuto;
  auto r = pipeline::bake(t.scene, st, *ctx_);
  ASSERT_TRUE(r) << r.status().to_string();
  const auto j = nlohmann::json::parse(r.value().denoise_json);
  EXPECT_EQ(j["method"], "oidn");
  EXPECT_EQ(j["chosen_by"], "auto");
  EXPECT_EQ(r.value().irradiance_denoised.size(), r.value().irradiance.size());
}

// (d) Only in the run ctest starts with LUXEL_OIDN_LIBRARY at a nonexistent
// file (tests/unit/post/CMakeLists.txt).
TEST(OidnMissing, FallsBackToAtrousAndSaysWhy) {
  if (!missing_library_run()) GTEST_SKIP() << "run by oidn_missing_test";
  auto lib = pipeline::load_oidn_uncached();
  ASSERT_FALSE(lib);
  EXPECT_NE(lib.status().message().find("nonexistent"), std::string::npos)
      << lib.status().message();
  device::Context& ctx = testing::shared_context();
  TwoCharts t = two_charts(1.0f, 1.0f, 0.5f);
  pipeline::BakeSettings s;
  s.atlas.resolution = 32;
  s.samples_per_texel = 4;
  s.max_bounces = 0;
  s.seed = 11;
  s.denoise = pipeline::Denoise::kOidn;
  auto r = pipeline::bake(t.scene, s, ctx);
  ASSERT_TRUE(r) << r.status().to_string();
  const auto j = nlohmann::json::parse(r.value().denoise_json);
  std::printf("  manifest denoise: %s\n", r.value().denoise_json.c_str());
  EXPECT_EQ(j["method"], "atrous");
  ASSERT_TRUE(j.contains("oidn"));
  EXPECT_EQ(j["oidn"].get<std::string>().rfind("not found: ", 0), 0u);
  EXPECT_NE(j["oidn"].get<std::string>().find("nonexistent"), std::string::npos);
  // The same map as an a-trous bake.
  s.denoise = pipeline::Denoise::kAtrous;
  auto a = pipeline::bake(t.scene, s, ctx);
  ASSERT_TRUE(a);
  EXPECT_EQ(r.value().irradiance_denoised, a.value().irradiance_denoised);
  // auto without the library: the raw map only, and the manifest says why.
  s.denoise = pipeline::Denoise::kAuto;
  auto raw = pipeline::bake(t.scene, s, ctx);
  ASSERT_TRUE(raw);
  EXPECT_TRUE(raw.value().irradiance_denoised.empty());
  const auto k = nlohmann::json::parse(raw.value().denoise_json);
  std::printf("  manifest denoise (auto): %s\n", raw.value().denoise_json.c_str());
  EXPECT_EQ(k["method"], "off");
  EXPECT_NE(k["oidn"].get<std::string>().find("nonexistent"), std::string::npos);
  EXPECT_EQ(raw.value().irradiance, a.value().irradiance) << "denoising never changes the raw map";
}

}  // namespace
}  // namespace luxel
