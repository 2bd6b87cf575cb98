// The bake engine against scenes with closed-form irradiance (DESIGN.md
// "Accuracy"): point light over a plane, uniform sky over an open
// plane, a closed emissive furnace box. Every covered texel is z-tested
// against the expected value with the standard error the engine reports
// itself (Šidák-corrected over texels), plus a pooled test of the mean
// relative deviation over all texels. Each check must also FAIL when a
// deliberate error is injected into the expected value, so it cannot pass
// trivially.
// Over 500 lines: each closed-form scene with its injected error sits beside
// the z-test helpers they all use.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>

#include "accel/triangle_soup.h"
#include "atlas/sample_info.h"
#include "bake/bake.h"
#include "bake/bake_policy.h"
#include "bake/scene_data.h"
#include "common/half.h"
#include "device/context.h"
#include "kernels/shared/sample_info.h"
#include "output/exr.h"
#include "support/device_context.h"
#include "support/test_scenes.h"

namespace luxel {
namespace {

struct Verdict {
  bool texels_ok = true;  // every texel within the Šidák bound
  bool pooled_ok = true;  // the mean relative deviation within its CI
  double max_z = 0, pooled_z = 0, mean_ratio = 0;
  size_t texels = 0;
  bool ok() const { return texels_ok && pooled_ok; }
};

// z-tests every fully covered texel's mean (channel 0..2) against
// expected(texel, channel); texels whose expected value is NaN are left
// out. The engine's standard error is rel_error * mean luminance; a floor of
// 1e-5 relative covers fp32 accumulation rounding when the sampling variance
// is ~0 (e.g. stratified direct light).
Verdict check(const pipeline::BakeResult& r, const std::function<double(uint32_t, int)>& expected,
              double family_alpha = 1e-3) {
  Verdict v;
  std::vector<double> rel;
  std::vector<std::array<double, 3>> zs;
  for (size_t t = 0; t < size_t(r.width) * r.height; ++t) {
    if (r.irradiance[t * 4 + 3] < 1.0f || r.samples[t] < 2) continue;
    if (std::isnan(expected(static_cast<uint32_t>(t), 0))) continue;
    const double lum = 0.2126 * r.irradiance[t * 4] + 0.7152 * r.irradiance[t * 4 + 1] +
                       0.0722 * r.irradiance[t * 4 + 2];
    std::array<double, 3> z{};
    for (int c = 0; c < 3; ++c) {
      const double e = expected(static_cast<uint32_t>(t), c);
      const double x = r.irradiance[t * 4 + static_cast<size_t>(c)];
      // Channel se from the luminance rel. error (grey transport: equal).
      const double se_rel = r.rel_error[t];
      const double se = std::sqrt(std::pow(se_rel * (lum > 0 ? x : 0), 2) + std::pow(1e-5 * e, 2));
      z[static_cast<size_t>(c)] = se > 0 ? (x - e) / se : (x == e ? 0 : INFINITY);
      if (c == 1) rel.push_back(e > 0 ? x / e - 1 : 0);
    }
    zs.push_back(z);
  }
  v.texels = zs.size();
  // Šidák: per-test alpha = 1 - (1 - family)^(1/m); two-sided normal bound.
  const double m = 3.0 * std::max<size_t>(zs.size(), 1);
  const double per_test = 1.0 - std::pow(1.0 - family_alpha, 1.0 / m);
  // Inverse normal tail by bisection on erfc.
  double lo = 0, hi = 40;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (std::erfc(mid / std::sqrt(2.0)) > per_test ? lo : hi) = mid;
  }
  const double bound = hi;
  for (const auto& z : zs)
    for (double zc : z) {
      v.max_z = std::max(v.max_z, std::fabs(zc));
      if (!(std::fabs(zc) <= bound)) v.texels_ok = false;
    }
  // Pooled: the mean relative deviation over texels with its sample CI.
  double mean = 0, var = 0;
  for (double x : rel) mean += x;
  mean /= std::max<size_t>(rel.size(), 1);
  for (double x : rel) var += (x - mean) * (x - mean);
  var /= std::max<size_t>(rel.size() - 1, 1);
  const double se = std::sqrt(var / std::max<size_t>(rel.size(), 1)) + 1e-5;
  v.pooled_z = mean / se;
  v.mean_ratio = 1 + mean;
  v.pooled_ok = std::fabs(v.pooled_z) <= 4.0;  // ~6e-5 two-sided
  std::printf("  %zu texels, max |z| %.2f (bound %.2f), mean ratio %.5f, pooled z %.2f\n", v.texels,
              v.max_z, bound, v.mean_ratio, v.pooled_z);
  return v;
}

// E = pi Le sum_j rho^j, j = 0..B, everywhere in the Lambert furnace.
double lambert_furnace_irradiance(float rho, float le, int bounces) {
  double sum = 0;
  for (int j = 0; j <= bounces; ++j) sum += std::pow(rho, j);
  return M_PI * le * sum;
}

// Every texel at the constant e, and a 2 % error in e caught.
void expect_constant_closed_form(const pipeline::BakeResult& r, double e) {
  auto expected = [&](double scale) { return [&, scale](uint32_t, int) { return scale * e; }; };
  EXPECT_TRUE(check(r, expected(1.0)).ok());
  EXPECT_FALSE(check(r, expected(1.02)).ok()) << "a 2 % error must be detected";
}

class ClosedFormTest : public testing::DeviceTest<> {
 protected:
  pipeline::BakeResult bake(const scene::Scene& s, const pipeline::BakeSettings& settings) {
    auto r = pipeline::bake(s, settings, *ctx_);
    EXPECT_TRUE(r) << r.status().to_string();
    if (!r) return {};
    return std::move(r.value());
  }

  static pipeline::BakeSettings settings(int resolution, uint32_t spp, int bounces) {
    pipeline::BakeSettings s;
    s.atlas.resolution = resolution;
    s.samples_per_texel = spp;
    s.max_bounces = bounces;
    s.paths_per_iteration = 1u << 16;
    s.seed = 7;
    return s;
  }

  // The point-light closed form; x_sign -1 for a mirrored plane.
  void check_point_light_over_plane(scene::Scene s, double x_sign);
  // The image-sky closed form, with or without first-bounce guiding.
  void check_equirect_sky(bool guiding);
};

// The mean of f over a texel's valid Hammersley positions (the quantity the
// engine estimates: each valid position is chosen with equal probability).
double texel_mean(const atlas::SampleInfo& info, uint32_t texel,
                  const std::function<double(double, double)>& f_uv) {
  const uint32_t off = info.offsets[texel];
  const uint64_t valid = uint64_t{info.words[off]} | (uint64_t{info.words[off + 1]} << 32);
  const uint32_t tx = texel % static_cast<uint32_t>(info.width),
                 ty = texel / static_cast<uint32_t>(info.width);
  double sum = 0;
  int n = 0;
  for (uint32_t i = 0; i < 64; ++i) {
    if (!(valid >> i & 1)) continue;
    const cl::float2 h = cl::lux_hammersley64(i);
    sum += f_uv((tx + h.x) / info.width, (ty + h.y) / info.height);
    ++n;
  }
  return sum / n;
}

// E = I cos(theta) / r^2 = I h / r^3, direct light only, over the open plane
// (atlas (u, v) -> world (x, z) = (x_sign (-1 + 2 v), -1 + 2 u); a mirrored
// instance flips x).
void ClosedFormTest::check_point_light_over_plane(scene::Scene s, double x_sign) {
  scene::Light light;
  light.type = scene::LightType::kPoint;
  light.intensity = 3.0f;
  light.position = {0.1f, 0.75f, -0.2f};
  s.lights.push_back(light);
  auto st = settings(32, 64, 0);
  auto r = bake(s, st);
  ASSERT_GT(r.covered_texels, 1000u);
  auto atlas = atlas::build_atlas(s, st.atlas);
  ASSERT_TRUE(atlas);
  auto info = atlas::build_sample_info(s, atlas.value());
  ASSERT_TRUE(info);
  auto expected = [&](double scale) {
    return [&, scale](uint32_t t, int) {
      return scale * texel_mean(info.value(), t, [&](double u, double v) {
               const double x = x_sign * (-1 + 2 * v) - light.position.x;
               const double z = -1 + 2 * u - light.position.z;
               const double h = light.position.y;
               const double r2 = x * x + z * z + h * h;
               return light.intensity * h / (r2 * std::sqrt(r2));
             });
    };
  };
  EXPECT_TRUE(check(r, expected(1.0)).ok());
  EXPECT_FALSE(check(r, expected(1.02)).ok()) << "a 2 % error must be detected";
}

TEST_F(ClosedFormTest, PointLightOverPlane) {
  check_point_light_over_plane(testing::open_plane(), 1.0);
}

TEST_F(ClosedFormTest, UniformSkyOverOpenPlane) {
  // E = pi L for an unoccluded plane under a constant sky; bounces add
  // nothing (nothing to hit), but run them to exercise the loop.
  scene::Scene s = testing::open_plane();
  auto st = settings(16, 256, 2);
  st.lights.sky.kind = pipeline::SkySettings::Kind::kConstant;
  st.lights.sky.color = {0.25f, 0.5f, 1.0f};
  st.lights.sky.intensity = 2.0f;
  auto r = bake(s, st);
  const double l[3] = {0.5, 1.0, 2.0};
  auto expected = [&](double scale) {
    return [&, scale](uint32_t, int c) { return scale * M_PI * l[c]; };
  };
  EXPECT_TRUE(check(r, expected(1.0)).ok());
  EXPECT_FALSE(check(r, expected(1.02)).ok()) << "a 2 % error must be detected";
  // The sky's light samples are cosine-weighted about the normal, like the
  // texel's first segment: both strategies give pi L for every sample, so
  // the estimate has no variance at all (float rounding aside).
  float worst = 0;
  for (size_t t = 0; t < r.rel_error.size(); ++t)
    if (r.irradiance[t * 4 + 3] > 0) worst = std::max(worst, r.rel_error[t]);
  EXPECT_LT(worst, 1e-5f) << "the sky-lit plane should converge with zero variance";
}

// The open plane under an instance transform that mirrors x (determinant
// -1; glTF 2.0 §3.7.4: its front face is the clockwise one). Its front still
// faces +y, so the closed forms of the open plane hold, with atlas (u, v) ->
// world (x, z) = (1 - 2 v, -1 + 2 u).
scene::Scene mirrored_open_plane() {
  scene::Scene s = testing::open_plane();
  s.instances[0].object_to_world.at(0, 0) = -1;
  return s;
}

// Under a uniform sky either side of a lone plane sees pi L, so the mirrored
// plane (lightmap rows 0 .. h/2) floats above a black ground (rows h/2 .. h,
// not tested) much wider than it: its front sees E = pi L, its back nearly
// nothing.
TEST_F(ClosedFormTest, UniformSkyOverMirroredPlane) {
  scene::Scene s;
  s.source_name = "mirrored_plane_over_black_ground";
  s.materials.push_back(testing::diffuse_material(0.5f));
  s.materials.push_back(testing::diffuse_material(0.0f));
  testing::add_quad(s, {-1, 0, -1}, {0, 0, 2}, {2, 0, 0}, 0, 0, 1, 0.5f, 0);
  s.instances[0].object_to_world.at(0, 0) = -1;
  testing::add_quad(s, {-20, -0.05f, -20}, {0, 0, 40}, {40, 0, 0}, 0, 0.5f, 1, 1, 1);
  const int res = 16;
  auto st = settings(res, 256, 2);
  st.lights.sky.kind = pipeline::SkySettings::Kind::kConstant;
  st.lights.sky.color = {0.25f, 0.5f, 1.0f};
  st.lights.sky.intensity = 2.0f;
  auto r = bake(s, st);
  ASSERT_GT(r.covered_texels, 200u);
  const double l[3] = {0.5, 1.0, 2.0};
  auto expected = [&](double scale) {
    return [&, scale](uint32_t t, int c) {
      return t / res < res / 2 ? scale * M_PI * l[c] : std::nan("");
    };
  };
  EXPECT_EQ(check(r, expected(1.0)).texels, size_t(res * res / 2));
  EXPECT_TRUE(check(r, expected(1.0)).ok());
  EXPECT_FALSE(check(r, expected(1.02)).ok()) << "a 2 % error must be detected";
}

TEST_F(ClosedFormTest, PointLightOverMirroredPlane) {
  check_point_light_over_plane(mirrored_open_plane(), -1.0);
}

void ClosedFormTest::check_equirect_sky(bool guiding) {
  // An image sky with a bright spot, importance-sampled (LUX_SKY_IMAGE).
  // Rows map to theta = (row + [0,1]) pi / H (kernels/shared/light.h), texels
  // are looked up nearest, so E = sum over upper-hemisphere texels of
  // L * (2 pi / W) * (sin^2 theta1 - sin^2 theta0) / 2, exactly.
  const int w = 32, h = 16;
  output::Image sky;
  sky.width = w;
  sky.height = h;
  sky.channels = 4;
  sky.pixels.assign(size_t(w) * h * 4, 0.2f);
  for (int y = 2; y < 4; ++y)
    for (int x = 5; x < 8; ++x)
      for (int c = 0; c < 3; ++c) sky.at(x, y, c) = 40.0f + 10.0f * c;
  const std::string path = ::testing::TempDir() + "/luxel_sky.exr";
  ASSERT_TRUE(output::write_exr(path, sky, {"R", "G", "B", "A"}).is_ok());
  double e[3] = {0, 0, 0};
  for (int y = 0; y < h / 2; ++y) {
    const double t0 = M_PI * y / h, t1 = M_PI * (y + 1) / h;
    const double band =
        (2 * M_PI / w) * 0.5 * (std::pow(std::sin(t1), 2) - std::pow(std::sin(t0), 2));
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) e[c] += sky.at(x, y, c) * band;
  }
  scene::Scene s = testing::open_plane();
  auto st = settings(16, 256, 1);
  st.lights.sky.kind = pipeline::SkySettings::Kind::kEquirect;
  st.lights.sky.equirect_path = path;
  st.lights.sky.rotation_degrees = 30;
  st.guiding = guiding;
  if (guiding) st.paths_per_iteration = 4096;  // 16 iterations to learn in
  auto r = bake(s, st);
  if (guiding) ASSERT_NE(r.features.find("guiding"), std::string::npos) << r.features;
  ASSERT_NE(r.features.find("sky_image"), std::string::npos) << r.features;
  auto expected = [&](double scale) {
    return [&, scale](uint32_t, int c) { return scale * e[c]; };
  };
  EXPECT_TRUE(check(r, expected(1.0)).ok());
  EXPECT_FALSE(check(r, expected(1.02)).ok()) << "a 2 % error must be detected";
}

TEST_F(ClosedFormTest, EquirectSkyOverOpenPlane) {
  check_equirect_sky(false);
}

// First-bounce guiding (kernels/bake/guiding.h) under the same sky: first
// directions from the learned mixture, MIS-weighted against the sky's
// importance sampling, must keep the closed form.
TEST_F(ClosedFormTest, GuidedEquirectSkyOverOpenPlane) {
  check_equirect_sky(true);
}

// Guiding in the furnace: every wall is an emitter, hit by guided first
// segments and sampled by NEE alike, with the texel point's MIS weighing NEE
// against the mixture's density; the estimate must stay exact. (With the
// cosine density in NEE's weight instead, this reads 0.25 % dark at z -3.0:
// the learned guide is nearly uniform here, so that defect stays below the
// pooled bound; docs/accuracy.md "First-bounce guiding".)
TEST_F(ClosedFormTest, GuidedFurnaceBox) {
  const float a = 0.5f, le = 0.25f;
  const int bounces = 6;
  auto st = settings(24, 512, bounces);  // most samples past the unguided epochs
  st.guiding = true;
  st.paths_per_iteration = 8192;
  auto r = bake(testing::furnace_box(a, le), st);
  ASSERT_GT(r.covered_texels, 300u);
  ASSERT_NE(r.features.find("guiding"), std::string::npos) << r.features;
  expect_constant_closed_form(r, lambert_furnace_irradiance(a, le, bounces));
  EXPECT_EQ(r.nonfinite_dropped, 0u);
}

TEST_F(ClosedFormTest, FurnaceBox) {
  // Closed box, albedo a, every wall emitting Le: with B bounces the
  // irradiance is pi Le (1 - a^(B+1)) / (1 - a) everywhere (-> pi Le/(1-a)).
  const float a = 0.5f, le = 0.25f;
  const int bounces = 6;
  scene::Scene s = testing::furnace_box(a, le);
  auto st = settings(24, 128, bounces);
  auto r = bake(s, st);
  ASSERT_GT(r.covered_texels, 300u);
  const double e = M_PI * le * (1 - std::pow(a, bounces + 1)) / (1 - a);
  auto expected = [&](double scale) { return [&, scale](uint32_t, int) { return scale * e; }; };
  EXPECT_TRUE(check(r, expected(1.0)).ok());
  EXPECT_FALSE(check(r, expected(1.02)).ok()) << "a 2 % error must be detected";
  EXPECT_EQ(r.nonfinite_dropped, 0u);
}

// Adaptive sampling (kernels/bake/adaptive.h) must stay unbiased: the same
// closed form with small batches, so that most paths are allocated by the
// texels' own error estimates. In the furnace every texel has the same true
// error, so the allocation follows the noise of each texel's estimate: the
// case where adaptive sampling's bias (Kirk and Arvo, thesis §3.3) would
// show, since a texel's allocation then correlates with its own samples.
TEST_F(ClosedFormTest, AdaptiveFurnaceBoxIsUnbiased) {
  const float a = 0.5f, le = 0.25f;
  const int bounces = 6;
  scene::Scene s = testing::furnace_box(a, le);
  auto st = settings(24, 128, bounces);
  st.adaptive = true;
  st.paths_per_iteration = 4096;
  auto r = bake(s, st);
  ASSERT_GT(r.covered_texels, 300u);
  float lo = INFINITY, hi = 0;
  for (size_t t = 0; t < r.samples.size(); ++t) {
    if (r.irradiance[t * 4 + 3] < 1.0f) continue;
    lo = std::min(lo, r.samples[t]);
    hi = std::max(hi, r.samples[t]);
  }
  EXPECT_GE(lo, 8.0f) << "the warm-up gives every texel adaptive_min_samples";
  EXPECT_GT(hi, 1.3f * lo) << "the allocation should follow the per-texel estimates";
  EXPECT_EQ(r.paths, uint64_t{128} * r.covered_texels) << "samples_per_texel is the mean";
  const double e = M_PI * le * (1 - std::pow(a, bounces + 1)) / (1 - a);
  auto expected = [&](double scale) { return [&, scale](uint32_t, int) { return scale * e; }; };
  EXPECT_TRUE(check(r, expected(1.0)).ok());
  EXPECT_FALSE(check(r, expected(1.02)).ok()) << "a 2 % error must be detected";
}

// White furnace of the BSDF (glTF 2.0 Appendix B with the Kulla-Conty 2017
// multiple-scattering compensation, kernels/shading/bsdf.h): a closed box
// whose walls emit Le and are a white metal (base colour 1, metallic 1, so
// Schlick's F = 1). Every bounce then reflects all the light it receives, so
// with B bounces the incident radiance is Le (B + 1) everywhere and
// E = pi Le (B + 1), at every roughness. Single-scattering GGX alone
// (Appendix B as written) falls short, increasingly with roughness
// (docs/accuracy.md lists the measured deficit).
TEST_F(ClosedFormTest, WhiteMetalFurnaceConservesEnergyAtEveryRoughness) {
  const float le = 0.25f;
  const int bounces = 4;
  for (float roughness : {0.2f, 0.5f, 1.0f}) {
    SCOPED_TRACE(strprintf("roughness %g", roughness));
    scene::Scene s = testing::furnace_box(1.0f, le);
    s.materials[0].metallic_factor = 1.0f;
    s.materials[0].roughness_factor = roughness;
    auto r = bake(s, settings(16, 256, bounces));
    ASSERT_GT(r.covered_texels, 100u);
    ASSERT_NE(r.features.find("specular"), std::string::npos) << r.features;
    const double e = M_PI * le * (bounces + 1);
    auto expected = [&](double scale) { return [&, scale](uint32_t, int) { return scale * e; }; };
    const Verdict v = check(r, expected(1.0));
    std::printf("  white metal, roughness %.1f: E / (pi Le (B + 1)) = %.5f\n", roughness,
                v.mean_ratio);
    EXPECT_TRUE(v.ok());
    EXPECT_FALSE(check(r, expected(1.02)).ok()) << "a 2 % error must be detected";
    EXPECT_EQ(r.nonfinite_dropped, 0u);
  }
}

// The Lambert variant at B = 4: walls of albedo rho (metallic 0, roughness
// 1: exactly Lambertian, the specular layer compiles out), E = pi Le sum_j
// rho^j for j = 0..B.
TEST_F(ClosedFormTest, LambertFurnaceAtFourBounces) {
  const float le = 0.25f, rho = 0.8f;
  const int bounces = 4;
  auto r = bake(testing::furnace_box(rho, le), settings(16, 256, bounces));
  ASSERT_GT(r.covered_texels, 100u);
  expect_constant_closed_form(r, lambert_furnace_irradiance(rho, le, bounces));
}

// The radiance cache (kernels/bake/radiance_cache.h) in the Lambert
// furnace: the irradiance is the same everywhere, so the cache's texel
// averaging costs nothing here and only its accounting shows. Gathers carry
// a third of the irradiance here. Injected through LUXEL_KERNEL_DIR, each of
// these fails: a cache that keeps the feeders' light-sampled share of the
// direct light (counted twice, +3.8 %), a gather light sample of weight 1
// although the cache keeps the BSDF-sampled share (+7.7 %), a gather that
// adds nothing from the cache (-34 %).
TEST_F(ClosedFormTest, RadianceCacheKeepsTheBounceCountInTheFurnace) {
  const float le = 0.25f, rho = 0.8f;
  const int bounces = 4;
  // 64^2: a texel is 1/11 of a wall, so most first hits lie beyond the
  // corner rule's 8 texel sizes and gather (at 16^2 almost none did).
  auto st = settings(64, 64, bounces);
  st.radiance_cache = true;
  st.adaptive = false;
  // Many iterations: shade reads the cache as the iterations before left it.
  st.paths_per_iteration = 1u << 15;
  auto r = bake(testing::furnace_box(rho, le), st);
  ASSERT_GT(r.covered_texels, 100u);
  ASSERT_NE(r.features.find("radiance_cache"), std::string::npos) << r.features;
  // The cache gathered: the bits differ from the same bake without it.
  st.radiance_cache = false;
  auto traced = bake(testing::furnace_box(rho, le), st);
  EXPECT_TRUE(r.irradiance != traced.irradiance);
  expect_constant_closed_form(r, lambert_furnace_irradiance(rho, le, bounces));
  EXPECT_EQ(r.nonfinite_dropped, 0u);
}

// The same furnace with the automatic batch, as users bake: iterations start
// at 16 samples per covered texel and grow to the paths already traced
// (BakePolicy::next_batch), so later iterations read a cache that is up to
// half as old as their own samples. The closed form must still hold.
TEST_F(ClosedFormTest, RadianceCacheWithGrowingIterationsKeepsTheFurnace) {
  const float le = 0.25f, rho = 0.8f;
  const int bounces = 4;
  auto st = settings(64, 64, bounces);
  st.radiance_cache = true;
  st.adaptive = false;
  st.paths_per_iteration = 0;
  auto r = bake(testing::furnace_box(rho, le), st);
  ASSERT_NE(r.features.find("radiance_cache"), std::string::npos) << r.features;
  // Growth happened: the first iterations (16 samples per texel) are smaller
  // than the batch the bake holds, and the bake needs more than them.
  const uint64_t first = pipeline::BakePolicy::learning_batch(r.covered_texels);
  ASSERT_LT(first, r.batch_paths);
  ASSERT_GT(uint64_t{64} * r.covered_texels, 2 * first);
  expect_constant_closed_form(r, lambert_furnace_irradiance(rho, le, bounces));
  EXPECT_EQ(r.nonfinite_dropped, 0u);
}

// Generated lightmap UVs (uv/generate.h), end to end. The furnace box
// without TEXCOORD_1 bakes with charts and packing chosen by Luxel
// (--uv auto), and every covered texel still reads the closed form
// pi Le sum_j rho^j: a chart mapped onto the wrong triangles, or padding that
// lets charts share texels, would show up as texels off the closed form.
TEST_F(ClosedFormTest, FurnaceWithGeneratedLightmapUvs) {
  const float le = 0.25f, rho = 0.5f;
  const int bounces = 3;
  double sum = 0;
  for (int j = 0; j <= bounces; ++j) sum += std::pow(rho, j);
  const double e = M_PI * le * sum;
  scene::Scene box = testing::furnace_box(rho, le);
  for (auto& m : box.meshes) {
    m.uv1.assign(m.positions.size(), Vec2{0, 0});
    m.has_lightmap_uvs = false;
  }
  auto r = bake(box, settings(48, 128, bounces));
  ASSERT_TRUE(r.uv_layout) << "TEXCOORD_1 is missing, so the layout must be generated";
  EXPECT_EQ(r.atlas.mode, atlas::AtlasMode::kGenerated);
  EXPECT_GT(r.covered_texels, 600u);
  auto expected = [&](double scale) { return [&, scale](uint32_t, int) { return scale * e; }; };
  EXPECT_TRUE(check(r, expected(1.0)).ok());
  EXPECT_FALSE(check(r, expected(1.02)).ok()) << "a 2 % error must be detected";
}

// DESIGN.md "stiff and extreme cases": scene scale from 1e-3 to 1e5 units
// (robust ray offsets, no self-intersection), and a nearly white closed room
// that needs many bounces (Russian roulette must stay unbiased).
TEST_F(ClosedFormTest, FurnaceBoxAtExtremeScalesAndHighAlbedo) {
  struct Case {
    float albedo, scale;
    int bounces;
  };
  for (const Case c : {Case{0.5f, 1e-3f, 6}, Case{0.5f, 1e5f, 6}, Case{0.9f, 1.0f, 40}}) {
    SCOPED_TRACE(strprintf("albedo %g scale %g bounces %d", c.albedo, c.scale, c.bounces));
    const float le = 0.25f;
    auto r = bake(testing::furnace_box(c.albedo, le, c.scale), settings(16, 128, c.bounces));
    ASSERT_GT(r.covered_texels, 100u);
    const double e = M_PI * le * (1 - std::pow(c.albedo, c.bounces + 1)) / (1 - c.albedo);
    auto expected = [&](double scale) { return [&, scale](uint32_t, int) { return scale * e; }; };
    EXPECT_TRUE(check(r, expected(1.0)).ok());
    EXPECT_FALSE(check(r, expected(1.03)).ok()) << "a 3 % error must be detected";
    EXPECT_EQ(r.nonfinite_dropped, 0u);
  }
}

// The open plane with a constant tangent-space normal map (a 2 x 2 RGBA16F
// texture, so (0.5, 0.5, 1) is exact) of scale `scale`, lit by a
// directional light of illuminance `lux` at normal incidence travelling
// along -to_light. `rgb`: the map's texel, or no map when empty.
scene::Scene normal_mapped_plane(const std::vector<float>& rgb, float scale, Vec3 to_light,
                                 float lux) {
  scene::Scene s = testing::open_plane();
  if (!rgb.empty()) {
    scene::Texture tex;
    tex.name = "normal map";
    tex.width = tex.height = 2;
    tex.format = scene::TexelFormat::kRGBA16F;
    for (int i = 0; i < 4; ++i)
      for (float c : {rgb[0], rgb[1], rgb[2], 1.0f}) tex.rgba16f.push_back(float_to_half(c));
    s.textures.push_back(tex);
    s.materials[0].normal_texture.texture = 0;
    s.materials[0].normal_scale = scale;
  }
  scene::Light light;
  light.type = scene::LightType::kDirectional;
  light.intensity = lux;
  light.direction = normalize(to_light) * -1.0f;
  s.lights.push_back(light);
  return s;
}

// The normal the map asks for, in double, from the texel as the device reads
// it (half-rounded): normalize(T x scale + B y scale + N z), (x, y, z) = 2 rgb
// - 1 (glTF 2.0 §3.9.3). The open plane's frame: N = +y, +u along +z (T),
// +v along +x, so the bitangent cross(N, T) * w with w = -1 (v runs along
// cross(N, T): a mirrored mapping) is -x. `bitangent_sign` and `use_scale`
// inject errors.
std::array<double, 3> mapped_normal(const std::vector<float>& rgb, double scale,
                                    double bitangent_sign = -1, bool use_scale = true) {
  double m[3];
  for (int k = 0; k < 3; ++k)
    m[k] = 2.0 * half_to_float(float_to_half(rgb[static_cast<size_t>(k)])) - 1.0;
  if (use_scale) m[0] *= scale, m[1] *= scale;
  // T = (0, 0, 1), B = (bitangent_sign, 0, 0), N = (0, 1, 0).
  std::array<double, 3> n = {m[1] * bitangent_sign, m[2], m[0]};
  const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  for (double& c : n) c /= len;
  return n;
}

TEST_F(ClosedFormTest, NormalMapTiltsIrradianceByItsAngle) {
  // Irradiance lightmaps integrate about the normal-mapped normal
  // (docs/accuracy.md "Normal maps"): under a directional light of
  // illuminance E, a texel whose map tilts the normal by theta receives
  // E cos(theta) at normal incidence, and E dot(n, l) in general. Direct
  // light from a delta source: no variance, so the bound is the 1e-5 floor.
  const std::vector<float> rgb = {0.5f, 0.8f, 0.9f};  // tilt along the bitangent
  const float scale = 0.5f, lux = 2.0f;
  auto st = settings(16, 16, 0);

  // 1. Normal incidence: E cos(theta), theta from the scaled map; on UV set
  // 0 and on UV set 1 (the open plane's TEXCOORD_1 maps like its TEXCOORD_0).
  for (int texcoord : {0, 1}) {
    SCOPED_TRACE(strprintf("texCoord %d", texcoord));
    scene::Scene plane = normal_mapped_plane(rgb, scale, {0, 1, 0}, lux);
    plane.materials[0].normal_texture.texcoord = texcoord;
    auto r = bake(plane, st);
    ASSERT_GT(r.covered_texels, 200u);
    EXPECT_NE(r.features.find("normal_map"), std::string::npos) << r.features;
    EXPECT_EQ(r.features.find("texcoord1") != std::string::npos, texcoord == 1) << r.features;
    auto expected = [&](bool use_scale) {
      const double cos_theta = mapped_normal(rgb, scale, -1, use_scale)[1];
      return [=](uint32_t, int) { return lux * cos_theta; };
    };
    EXPECT_TRUE(check(r, expected(true)).ok());
    EXPECT_FALSE(check(r, expected(false)).ok()) << "ignoring the scale must be detected";
  }
  // 2. Oblique light in the bitangent's plane: E dot(n, l); the bitangent's
  // sign decides which way the normal leans.
  const Vec3 to_light = normalize(Vec3{-0.5f, 1.0f, 0.0f});
  {
    auto r = bake(normal_mapped_plane(rgb, scale, to_light, lux), st);
    auto expected = [&](double sign) {
      const auto n = mapped_normal(rgb, scale, sign);
      const double e = lux * (n[0] * to_light.x + n[1] * to_light.y + n[2] * to_light.z);
      return [=](uint32_t, int) { return e; };
    };
    EXPECT_TRUE(check(r, expected(-1)).ok());
    EXPECT_FALSE(check(r, expected(+1)).ok()) << "the wrong tangent sign must be detected";
  }
  // 3. A flat map (0.5, 0.5, 1) changes nothing: the bake without a map,
  // texel by texel (and E cos of the light's angle).
  {
    auto flat = bake(normal_mapped_plane({0.5f, 0.5f, 1.0f}, scale, to_light, lux), st);
    auto none = bake(normal_mapped_plane({}, scale, to_light, lux), st);
    EXPECT_EQ(none.features.find("normal_map"), std::string::npos) << none.features;
    ASSERT_EQ(flat.irradiance.size(), none.irradiance.size());
    EXPECT_TRUE(check(flat, [&](uint32_t t, int c) {
                  return double(none.irradiance[t * 4 + static_cast<size_t>(c)]);
                }).ok());
    EXPECT_TRUE(check(flat, [&](uint32_t, int) { return lux * double(to_light.y); }).ok());
    EXPECT_FALSE(check(flat, [&](uint32_t, int) { return lux * 1.02 * double(to_light.y); }).ok())
        << "a 2 % error must be detected";
  }
  // 4. With a directional encoding the texel point is not mapped (the
  // runtime applies the map when it reconstructs): the irradiance that comes
  // with the encoding is about the unmapped normal, E at normal incidence;
  // the map still shades bounces, so it is compiled.
  {
    auto enc = st;
    enc.encodings.names = {"sh2"};
    auto r = bake(normal_mapped_plane(rgb, scale, {0, 1, 0}, lux), enc);
    ASSERT_EQ(r.encodings.size(), 1u);
    EXPECT_NE(r.features.find("normal_map"), std::string::npos) << r.features;
    EXPECT_TRUE(check(r, [&](uint32_t, int) { return double(lux); }).ok());
    const double cos_theta = mapped_normal(rgb, scale)[1];
    EXPECT_FALSE(check(r, [&](uint32_t, int) { return lux * cos_theta; }).ok())
        << "a mapped texel point must be detected";
  }
}

// The device tangents of the open plane (prepare_scene_data): world +u,
// the generated sign (w = -1: its v runs along cross(N, T)), and, under an
// instance that mirrors x, the same tangent with w = +1: in world space the
// plane's v then runs along -x, so the bitangent cross(N, T) w must flip
// with the transform's determinant.
TEST(NormalMapTangents, MirroringInstanceFlipsTheBitangentSign) {
  for (bool mirrored : {false, true}) {
    SCOPED_TRACE(mirrored ? "mirrored" : "identity");
    scene::Scene s = normal_mapped_plane({0.5f, 0.8f, 0.9f}, 1.0f, {0, 1, 0}, 1.0f);
    if (mirrored) s.instances[0].object_to_world.at(0, 0) = -1;
    auto soup = accel::build_triangle_soup(s);
    ASSERT_TRUE(soup) << soup.status().to_string();
    pipeline::BakeSettings st;
    st.atlas.resolution = 16;
    auto atlas = atlas::build_atlas(s, st.atlas);
    ASSERT_TRUE(atlas) << atlas.status().to_string();
    auto data = pipeline::prepare_scene_data(s, soup.value(), atlas.value(),
                                             std::vector<int32_t>(soup.value().size(), -1));
    ASSERT_TRUE(data) << data.status().to_string();
    EXPECT_TRUE(data.value().uses_normal_map);
    ASSERT_EQ(data.value().tangents.size(), soup.value().size());
    for (const cl::LuxTriangleTangents& t : data.value().tangents)
      for (const cl::float4& v : {t.t0, t.t1, t.t2}) {
        EXPECT_NEAR(v.x, 0, 1e-6);
        EXPECT_NEAR(v.y, 0, 1e-6);
        EXPECT_NEAR(v.z, 1, 1e-6);
        EXPECT_EQ(v.w, mirrored ? 1.0f : -1.0f);
      }
    // Scenes without a normal map get no tangent data.
    s.materials[0].normal_texture.texture = -1;
    auto plain = pipeline::prepare_scene_data(s, soup.value(), atlas.value(),
                                              std::vector<int32_t>(soup.value().size(), -1));
    ASSERT_TRUE(plain);
    EXPECT_FALSE(plain.value().uses_normal_map);
    EXPECT_TRUE(plain.value().tangents.empty());
  }
}

// Normal maps at bounce vertices: the Lambert furnace with every wall
// normal-mapped by a constant tilt theta. A Lambertian lobe about a normal
// tilted by theta keeps k = (1 + cos theta) / 2 of its clamped-cosine mass
// above the geometric surface (directions below it carry nothing), so each
// bounce reflects rho k of a uniform radiance field and the texel point,
// integrating about the mapped normal, sees pi k of it:
//   E = pi Le k sum_j (rho k)^j, j = 0..B.
// Bounces that ignored the map would reflect rho (the plain furnace's sum);
// a texel point that ignored it would miss the leading k.
TEST_F(ClosedFormTest, NormalMappedLambertFurnace) {
  const float le = 0.25f, rho = 0.8f;
  const int bounces = 4;
  const std::vector<float> rgb = {0.5f, 0.8f, 0.9f};
  scene::Scene s = testing::furnace_box(rho, le);
  scene::Texture tex;
  tex.width = tex.height = 1;
  tex.format = scene::TexelFormat::kRGBA16F;
  for (float c : {rgb[0], rgb[1], rgb[2], 1.0f}) tex.rgba16f.push_back(float_to_half(c));
  s.textures.push_back(tex);
  s.materials[0].normal_texture.texture = 0;
  auto r = bake(s, settings(16, 256, bounces));
  ASSERT_GT(r.covered_texels, 100u);
  ASSERT_NE(r.features.find("normal_map"), std::string::npos) << r.features;
  const double k = (1 + mapped_normal(rgb, 1.0)[1]) / 2;
  auto furnace = [&](double texel_k, double bounce_k) {
    double sum = 0;
    for (int j = 0; j <= bounces; ++j) sum += std::pow(rho * bounce_k, j);
    const double e = M_PI * le * texel_k * sum;
    return [e](uint32_t, int) { return e; };
  };
  std::printf("  k = %.5f\n", k);
  EXPECT_TRUE(check(r, furnace(k, k)).ok());
  EXPECT_FALSE(check(r, furnace(k, 1)).ok()) << "bounces ignoring the map must be detected";
  EXPECT_FALSE(check(r, furnace(1, k)).ok()) << "a texel point ignoring the map must be detected";
  EXPECT_EQ(r.nonfinite_dropped, 0u);
}

TEST_F(ClosedFormTest, SameSeedIsBitIdenticalOtherSeedDiffers) {
  scene::Scene s = testing::furnace_box(0.5f, 0.25f);
  auto st = settings(16, 16, 3);
  auto a = bake(s, st);
  auto b = bake(s, st);
  ASSERT_EQ(a.irradiance.size(), b.irradiance.size());
  EXPECT_EQ(0, std::memcmp(a.irradiance.data(), b.irradiance.data(), a.irradiance.size() * 4));
  st.seed = 8;
  auto c = bake(s, st);
  EXPECT_NE(0, std::memcmp(a.irradiance.data(), c.irradiance.data(), a.irradiance.size() * 4));
}

TEST_F(ClosedFormTest, NonFiniteSamplesAreCountedAndDropped) {
  // A light so bright that I / r^2 overflows fp32: every sample is +inf.
  scene::Scene s = testing::open_plane();
  scene::Light light;
  light.type = scene::LightType::kPoint;
  light.intensity = 3e38f;
  light.position = {0, 1e-3f, 0};
  s.lights.push_back(light);
  auto r = bake(s, settings(8, 4, 0));
  EXPECT_GT(r.nonfinite_dropped, 0u);
  for (float x : r.irradiance) EXPECT_TRUE(std::isfinite(x));
}

TEST_F(ClosedFormTest, StopsOnTargetErrorAndTime) {
  scene::Scene s = testing::furnace_box(0.5f, 0.25f);
  auto st = settings(16, 0, 2);
  st.target_error = 0.05;
  auto r = bake(s, st);
  EXPECT_EQ(r.termination, pipeline::Termination::kError);
  EXPECT_LE(r.error, 0.05);
  EXPECT_FALSE(r.series.empty());
  st.target_error = 0;
  st.time_budget_s = 0.5;
  auto t = bake(s, st);
  EXPECT_EQ(t.termination, pipeline::Termination::kTime);
  // The rule fires once the budget is spent, never before.
  EXPECT_GE(t.seconds, 0.5);
}

TEST_F(ClosedFormTest, InvalidSettingsNameTheField) {
  scene::Scene s = testing::open_plane();
  auto st = settings(16, 16, 1);
  st.max_bounces = 99;
  auto r = pipeline::bake(s, st, *ctx_);
  ASSERT_FALSE(r);
  EXPECT_NE(r.status().message().find("max_bounces"), std::string::npos) << r.status().message();
  // Guiding with directional encodings, whose moments need uniform first
  // directions (kernels/bake/guiding.h); with irradiance only it bakes.
  st.max_bounces = 1;
  st.guiding = true;
  st.encodings.names = {"sh2"};
  r = pipeline::bake(s, st, *ctx_);
  ASSERT_FALSE(r);
  EXPECT_NE(r.status().message().find("settings.guiding"), std::string::npos)
      << r.status().message();
  st.encodings.names.clear();
  r = pipeline::bake(s, st, *ctx_);
  EXPECT_TRUE(r) << r.status().to_string();
}

}  // namespace
}  // namespace luxel
