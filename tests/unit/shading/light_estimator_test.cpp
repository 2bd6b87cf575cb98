// Next-event estimation end to end (thesis §6.1): the Monte Carlo estimate of
// irradiance at a point, sum over samples of radiance cos / pdf using only
// light samples (no occlusion), agrees with closed forms within a confidence
// interval. These check radiance, pdf and selection together, absolutely.
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "shading_probe.h"
#include "test_scenes.h"

namespace luxel::pipeline {
namespace {

using test::Rng;
using test::SceneBuilder;

constexpr double kPi = 3.14159265358979323846;

struct Estimate {
  std::array<double, 3> mean{}, stderr_{};
};

// Irradiance at p with normal n from n samples of the table's lights.
Estimate estimate_irradiance(const LightTable& table, Vec3 p, Vec3 n, size_t count, uint64_t seed) {
  auto probe = test::LightProbe::create(table);
  EXPECT_TRUE(probe.is_ok()) << probe.status().to_string();
  if (!probe.is_ok()) return {};
  Rng rng(seed);
  std::vector<cl::float4> r(count);
  for (auto& v : r) v = rng.uniform4();
  auto s = (*probe)->sample_at(p, r, n);
  EXPECT_TRUE(s.is_ok()) << s.status().to_string();
  if (!s.is_ok()) return {};
  std::array<double, 3> sum{}, sum2{};
  for (size_t i = 0; i < count; ++i) {
    if (!s->ok(i)) continue;
    const Vec3 wi = test::xyz(s->wi_pdf[i]);
    const double cos = std::max(0.0, static_cast<double>(dot(wi, n)));
    const double w = cos / s->wi_pdf[i].w;
    const double rad[3] = {s->radiance_dist[i].x, s->radiance_dist[i].y, s->radiance_dist[i].z};
    for (int c = 0; c < 3; ++c) {
      sum[static_cast<size_t>(c)] += rad[c] * w;
      sum2[static_cast<size_t>(c)] += rad[c] * w * rad[c] * w;
    }
  }
  Estimate e;
  for (size_t c = 0; c < 3; ++c) {
    e.mean[c] = sum[c] / count;
    const double var = std::max(sum2[c] / count - e.mean[c] * e.mean[c], 0.0);
    e.stderr_[c] = std::sqrt(var / count);
  }
  return e;
}

// 5 standard errors (about 1 in 1.7 million for a correct estimator), plus
// float rounding for zero-variance (delta light) estimates.
void expect_agrees(const Estimate& e, std::array<double, 3> exact, const char* what) {
  for (size_t c = 0; c < 3; ++c) {
    EXPECT_NEAR(e.mean[c], exact[c], 5 * e.stderr_[c] + 2e-5 * std::fabs(exact[c]))
        << what << " channel " << c << " (stderr " << e.stderr_[c] << ")";
  }
}

Bounds3 unit_bounds() {
  Bounds3 b;
  b.extend(Vec3{-1, -1, -1});
  b.extend(Vec3{1, 1, 1});
  return b;
}

TEST(LightEstimator, PointSpotAndDirectionalLightsTogether) {
  SceneBuilder b;
  const Vec3 p{0.2f, 0, -0.1f}, n = normalize(Vec3{0.3f, 1, 0.2f});
  const Vec3 point{1, 2, 0.5f}, spot{-0.5f, 3, 0};
  b.add_point(point, {1, 0.5f, 0.25f}, 8.0f);
  b.add_spot(spot, p - spot, {0.2f, 1, 0.4f}, 30.0f, 0.2f,
             0.5f);  // aimed at p: inside the inner cone
  b.add_directional({0.5f, -1, 0.3f}, {0.7f, 0.8f, 0.9f}, 2.0f);
  auto table = build_light_table(b.s, b.soup(), {}, unit_bounds());
  ASSERT_TRUE(table.is_ok()) << table.status().to_string();
  std::array<double, 3> exact{};
  auto add = [&](Vec3 intensity, Vec3 from) {  // I cos / r^2
    const Vec3 d = from - p;
    const double r2 = dot(d, d), cos = dot(normalize(d), n);
    for (int c = 0; c < 3; ++c) exact[static_cast<size_t>(c)] += intensity[c] * cos / r2;
  };
  add(Vec3{1, 0.5f, 0.25f} * 8.0f, point);
  add(Vec3{0.2f, 1, 0.4f} * 30.0f, spot);
  const double cos_dir = dot(normalize(Vec3{-0.5f, 1, -0.3f}), n);
  for (int c = 0; c < 3; ++c)
    exact[static_cast<size_t>(c)] += Vec3{0.7f, 0.8f, 0.9f}[c] * 2.0 * cos_dir;
  expect_agrees(estimate_irradiance(table.value(), p, n, 100000, 11), exact,
                "point + spot + directional");
}

TEST(LightEstimator, SpotFalloffBetweenTheCones) {
  SceneBuilder b;
  const Vec3 spot{0, 2, 0};
  b.add_spot(spot, {0, -1, 0}, {1, 1, 1}, 10.0f, 0.2f, 0.6f);
  auto table = build_light_table(b.s, b.soup(), {}, unit_bounds());
  ASSERT_TRUE(table.is_ok());
  // A point 0.4 rad off the axis: glTF falloff ((cos a - cos o)/(cos i - cos o))^2.
  const Vec3 p{2 * std::tan(0.4f), 0, 0}, n{0, 1, 0};
  const double cd = std::cos(0.4), ci = std::cos(0.2), co = std::cos(0.6);
  const double att = std::pow((cd - co) / (ci - co), 2);
  const Vec3 d = spot - p;
  const double e = 10.0 * att * dot(normalize(d), n) / dot(d, d);
  expect_agrees(estimate_irradiance(table.value(), p, n, 1000, 12), {e, e, e}, "spot falloff");
  // Outside the outer cone nothing arrives.
  const Estimate out = estimate_irradiance(table.value(), {3, 0, 0}, n, 1000, 13);
  EXPECT_EQ(out.mean[0], 0.0);
}

TEST(LightEstimator, SunDiscsGiveTheirIlluminanceTimesCos) {
  for (float radius : {0.27f, 5.0f}) {
    LightSettings s;
    s.sun.enabled = true;
    s.sun.direction = {0.4f, -1, -0.2f};
    s.sun.color = {1, 0.9f, 0.8f};
    s.sun.illuminance = 1000;
    s.sun.angular_radius_degrees = radius;
    auto table = build_light_table(scene::Scene{}, accel::TriangleSoup{}, s, Bounds3{});
    ASSERT_TRUE(table.is_ok());
    // A disc entirely above the horizon gives exactly E cos(theta_centre).
    const Vec3 n = normalize(Vec3{0.1f, 1, 0.3f});
    const double cos = dot(normalize(Vec3{-0.4f, 1, 0.2f}), n);
    const std::array<double, 3> exact{1000 * cos, 900 * cos, 800 * cos};
    expect_agrees(estimate_irradiance(table.value(), {0, 0, 0}, n, 100000, 14), exact,
                  radius < 1 ? "sun 0.27 deg" : "sun 5 deg");
  }
}

// Irradiance from a uniformly emitting polygon entirely above p's horizon
// (Lambert's formula): E = L/2 |sum_i angle(r_i, r_i+1) n . unit(r_i x r_i+1)|.
double polygon_irradiance(double radiance, Vec3 p, Vec3 n, const std::vector<Vec3>& poly) {
  double sum = 0;
  for (size_t i = 0; i < poly.size(); ++i) {
    const Vec3 a = normalize(poly[i] - p), b = normalize(poly[(i + 1) % poly.size()] - p);
    const double angle = std::acos(std::clamp(static_cast<double>(dot(a, b)), -1.0, 1.0));
    sum += angle * dot(normalize(cross(a, b)), n);
  }
  return 0.5 * radiance * std::fabs(sum);
}

TEST(LightEstimator, LargeEmissiveTriangleMatchesLambertsFormula) {
  const std::vector<Vec3> tri = {
      {-6, 1.5f, -4}, {5, 1, -5}, {1, 2, 7}};  // front face down (winding)
  const Vec3 p{0.3f, 0, 0.2f}, n = normalize(Vec3{0.2f, 1, -0.1f});
  for (bool double_sided : {false, true}) {
    SceneBuilder b;
    const int glow = b.add_emitter({2, 1, 0.5f}, double_sided);
    b.add_triangles(tri, glow);
    auto table = build_light_table(b.s, b.soup(), {}, unit_bounds());
    ASSERT_TRUE(table.is_ok());
    ASSERT_LT(table->lights[0].shape.y, 0) << "the test wants the front face towards p";
    const double e = polygon_irradiance(1.0, p, n, tri);
    expect_agrees(estimate_irradiance(table.value(), p, n, 200000, 15), {2 * e, e, 0.5 * e},
                  double_sided ? "double-sided triangle" : "triangle");
  }
  // From behind, a one-sided emitter sends nothing; a double-sided one the same.
  const Vec3 above{0.3f, 4, 0.2f}, down{0, -1, 0};
  const double e_above = polygon_irradiance(1.0, above, down, tri);
  for (bool double_sided : {false, true}) {
    SceneBuilder b;
    b.add_triangles(tri, b.add_emitter({1, 1, 1}, double_sided));
    auto table = build_light_table(b.s, b.soup(), {}, unit_bounds());
    ASSERT_TRUE(table.is_ok());
    const Estimate est = estimate_irradiance(table.value(), above, down, 100000, 16);
    if (double_sided) {
      expect_agrees(est, {e_above, e_above, e_above}, "double-sided from behind");
    } else {
      EXPECT_EQ(est.mean[1], 0.0) << "one-sided emitter seen from behind";
    }
  }
}

TEST(LightEstimator, ConstantSkyGivesPiLOverTheHemisphere) {
  LightSettings s;
  s.sky.kind = SkySettings::Kind::kConstant;
  s.sky.color = {0.2f, 0.5f, 1.0f};
  s.sky.intensity = 3;
  auto table = build_light_table(scene::Scene{}, accel::TriangleSoup{}, s, Bounds3{});
  ASSERT_TRUE(table.is_ok());
  const Vec3 n = normalize(Vec3{1, 0.5f, -0.3f});  // any orientation: the sky surrounds p
  expect_agrees(estimate_irradiance(table.value(), {0, 0, 0}, n, 200000, 17),
                {kPi * 0.6, kPi * 1.5, kPi * 3.0}, "constant sky");
}

TEST(LightEstimator, MixedLightsSumTheirIrradiance) {
  const std::vector<Vec3> tri = {{-2, 2, -2}, {3, 2, -1}, {0, 2.5f, 3}};
  SceneBuilder b;
  b.add_triangles(tri, b.add_emitter({1, 1, 1}));
  const Vec3 point{2, 1, 1}, p{0, 0, 0}, n{0, 1, 0};
  b.add_point(point, {1, 1, 1}, 5.0f);
  LightSettings s;
  s.sky.kind = SkySettings::Kind::kConstant;
  s.sky.intensity = 0.5f;
  auto table = build_light_table(b.s, b.soup(), s, unit_bounds());
  ASSERT_TRUE(table.is_ok());
  ASSERT_EQ(table->lights.size(), 3u);
  const double e = polygon_irradiance(1.0, p, n, tri) +
                   5.0 * dot(normalize(point), n) / dot(point, point) + kPi * 0.5;
  expect_agrees(estimate_irradiance(table.value(), p, n, 300000, 18), {e, e, e},
                "triangle + point + sky");
}

}  // namespace
}  // namespace luxel::pipeline
