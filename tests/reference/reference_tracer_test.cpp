// The CPU reference tracer against closed forms, so that the agreement test
// (tests/integration) compares the engine with something itself checked:
//   - a furnace: a closed (tessellated) sphere whose inside emits L_e and
//     reflects with albedo rho everywhere, where E = pi L_e (1 + rho + ...
//     + rho^B) at every point of every texel;
//   - direct light from a parallel rectangle above a black floor (the
//     point-to-rectangle form factor, Howell's catalogue C-11), single- and
//     double-sided;
//   - the statistics helpers against tabulated Student-t quantiles;
//   - the glTF BRDF (reference_bsdf.h): its E(mu) table and its directional
//     albedo against a brute-force integral over the hemisphere, its
//     sampling against that albedo, and a white-metal furnace (F = 1: with
//     the compensation every direction reflects exactly 1, so E = pi L_e
//     (B + 1)).
// Each comparison is a per-texel z-test (Šidák over texels) plus a test
// that a deliberate error (one bounce too few, 3 % too bright, no
// compensation) is detected.
// Over 500 lines: the reference tracer's closed forms and its injected errors
// share one set of scenes.
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdio>
#include <string>

#include "atlas/atlas.h"
#include "atlas/sample_info.h"
#include "reference/agreement_stats.h"
#include "reference/cpu_lightmap_tracer.h"
#include "reference/pcg32.h"
#include "reference/reference_bsdf.h"

namespace luxel::reference {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kFamilyAlpha = 1e-3;

// One mesh, one instance; flat-shaded quads and triangles appended with
// their lightmap UVs.
struct FacetSceneBuilder {
  scene::Scene s;
  FacetSceneBuilder() {
    s.source_name = "reference_tracer_test";
    s.meshes.emplace_back();
    s.meshes[0].name = "quads";
    scene::Instance inst;
    inst.name = "quads";
    inst.mesh = 0;
    s.instances.push_back(inst);
  }
  int material(Vec3 albedo, Vec3 emission, bool double_sided = false, float metallic = 0,
               float roughness = 1) {
    scene::Material m;
    m.name = "m" + std::to_string(s.materials.size());
    m.base_color_factor = {albedo.x, albedo.y, albedo.z, 1};
    m.metallic_factor = metallic;
    m.roughness_factor = roughness;
    m.emissive_factor = emission;
    m.double_sided = double_sided;
    s.materials.push_back(m);
    return static_cast<int>(s.materials.size()) - 1;
  }
  // Corners in cyclic order; the winding is fixed to face `normal`. The chart
  // is the UV rectangle [u0, u1] x [v0, v1].
  void quad(std::array<Vec3, 4> c, Vec3 normal, float u0, float v0, float u1, float v1, int mat) {
    if (dot(cross(c[1] - c[0], c[2] - c[0]), normal) < 0) std::swap(c[1], c[3]);
    scene::Mesh& m = s.meshes[0];
    const auto base = static_cast<uint32_t>(m.positions.size());
    const Vec2 uv[4] = {{u0, v0}, {u1, v0}, {u1, v1}, {u0, v1}};
    for (int k = 0; k < 4; ++k) {
      m.positions.push_back(c[static_cast<size_t>(k)]);
      m.normals.push_back(normalize(normal));
      m.uv0.push_back(uv[k]);
      m.uv1.push_back(uv[k]);
    }
    m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
    m.triangle_material.insert(m.triangle_material.end(), {mat, mat});
  }
  // A triangle facing the origin (the inside of a sphere about it), with its
  // flat normal.
  void triangle(std::array<Vec3, 3> p, std::array<Vec2, 3> uv, int mat) {
    const Vec3 centroid = (p[0] + p[1] + p[2]) * (1.0f / 3.0f);
    Vec3 n = cross(p[1] - p[0], p[2] - p[0]);
    if (dot(n, centroid) > 0) {
      std::swap(p[1], p[2]);
      std::swap(uv[1], uv[2]);
      n = n * -1.0f;
    }
    scene::Mesh& m = s.meshes[0];
    const auto base = static_cast<uint32_t>(m.positions.size());
    for (size_t k = 0; k < 3; ++k) {
      m.positions.push_back(p[k]);
      m.normals.push_back(normalize(n));
      m.uv0.push_back(uv[k]);
      m.uv1.push_back(uv[k]);
    }
    m.indices.insert(m.indices.end(), {base, base + 1, base + 2});
    m.triangle_material.push_back(mat);
  }
};

// The furnace: the inside of a unit sphere tessellated into flat facets
// (flat normals, so E is exactly the closed form), one material, charted by
// latitude and longitude. A sphere rather than a box: area-sampled NEE from
// one facet to its near-coplanar neighbours stays well-behaved, whereas a
// box's right-angled edges give samples near an edge a variance heavy-tailed
// enough to spoil a per-texel z-test of 256 samples.
scene::Scene furnace(Vec3 albedo, Vec3 emission, float metallic = 0, float roughness = 1) {
  FacetSceneBuilder b;
  const int mat = b.material(albedo, emission, false, metallic, roughness);
  constexpr int kLat = 12, kLon = 24;
  // Vertices shared by neighbouring facets must be bit-identical (no cracks):
  // the poles and the seam at phi = 2 pi are special-cased.
  auto at = [](int i, int j) {
    if (i == 0 || i == kLat) return Vec3{0, i == 0 ? 1.0f : -1.0f, 0};
    const double theta = kPi * i / kLat, phi = 2 * kPi * (j % kLon) / kLon;
    return Vec3{static_cast<float>(std::sin(theta) * std::cos(phi)),
                static_cast<float>(std::cos(theta)),
                static_cast<float>(std::sin(theta) * std::sin(phi))};
  };
  auto uv = [](double i, double j) {
    return Vec2{static_cast<float>(j / kLon), static_cast<float>(i / kLat)};
  };
  for (int i = 0; i < kLat; ++i) {
    for (int j = 0; j < kLon; ++j) {
      if (i == 0) {  // around the north pole
        b.triangle({at(0, j), at(1, j), at(1, j + 1)}, {uv(0, j + 0.5), uv(1, j), uv(1, j + 1)},
                   mat);
      } else if (i == kLat - 1) {  // around the south pole
        b.triangle({at(i, j), at(i + 1, j), at(i, j + 1)},
                   {uv(i, j), uv(i + 1, j + 0.5), uv(i, j + 1)}, mat);
      } else {
        b.triangle({at(i, j), at(i + 1, j), at(i + 1, j + 1)},
                   {uv(i, j), uv(i + 1, j), uv(i + 1, j + 1)}, mat);
        b.triangle({at(i, j), at(i + 1, j + 1), at(i, j + 1)},
                   {uv(i, j), uv(i + 1, j + 1), uv(i, j + 1)}, mat);
      }
    }
  }
  return b.s;
}

// Black floor [-1, 1]^2 at y = 0 under the emitter [x0, x1] x [z0, z1] at
// height h facing `emitter_normal`.
struct RectangleSetup {
  float x0 = -0.3f, x1 = 0.5f, z0 = -0.4f, z1 = 0.2f, h = 0.5f;
};
scene::Scene rectangle_over_floor(const RectangleSetup& r, Vec3 emission, Vec3 emitter_normal,
                                  bool double_sided) {
  FacetSceneBuilder b;
  const int floor = b.material({0, 0, 0}, {0, 0, 0});
  const int light = b.material({0, 0, 0}, emission, double_sided);
  b.quad({Vec3{-1, 0, -1}, Vec3{1, 0, -1}, Vec3{1, 0, 1}, Vec3{-1, 0, 1}}, {0, 1, 0}, 0.02f, 0.02f,
         0.66f, 0.66f, floor);
  b.quad(
      {Vec3{r.x0, r.h, r.z0}, Vec3{r.x1, r.h, r.z0}, Vec3{r.x1, r.h, r.z1}, Vec3{r.x0, r.h, r.z1}},
      emitter_normal, 0.72f, 0.72f, 0.97f, 0.97f, light);
  return b.s;
}

// Form factor from a point to the rectangle [0, u] x [0, v] (signed sides)
// lying parallel at height h with a corner straight above the point.
double corner_form_factor(double u, double v, double h) {
  const double a = std::abs(u) / h, b = std::abs(v) / h;
  const double sa = std::sqrt(1 + a * a), sb = std::sqrt(1 + b * b);
  const double f = (a / sa * std::atan(b / sa) + b / sb * std::atan(a / sb)) / (2 * kPi);
  return (u < 0) != (v < 0) ? -f : f;
}

// Irradiance at floor point (x, z) from the rectangle of radiance 1.
double rectangle_irradiance(const RectangleSetup& r, double x, double z) {
  const double f =
      corner_form_factor(r.x1 - x, r.z1 - z, r.h) - corner_form_factor(r.x0 - x, r.z1 - z, r.h) -
      corner_form_factor(r.x1 - x, r.z0 - z, r.h) + corner_form_factor(r.x0 - x, r.z0 - z, r.h);
  return kPi * f;
}

struct Agreement {
  size_t tests = 0, failures = 0;
  double max_abs_t = 0;
  double pooled_ratio = 0;  // sum of reference means / sum of expected (luminance)
  double pooled_z = 0;      // (sum reference - sum expected) / its standard error (luminance)
  // Some texel fails its Šidák-corrected test, or the pooled test fails at
  // the family level.
  bool detected() const {
    return failures > 0 || std::abs(pooled_z) > two_sided_critical(kFamilyAlpha, kKnownVariance);
  }
};

// Per-texel, per-colour z-tests of the reference (times `scale`) against
// expected[texel * 3 + c], which is exact.
Agreement check(const ReferenceLightmap& ref, const std::vector<double>& expected,
                double scale = 1.0) {
  Agreement a;
  std::vector<size_t> texels;
  for (size_t t = 0; t < ref.coverage.size(); ++t)
    if (ref.coverage[t] > 0) texels.push_back(t);
  a.tests = texels.size() * 3;
  const double alpha = sidak_alpha(kFamilyAlpha, a.tests);
  double sum_ref = 0, sum_expected = 0, var_sum = 0;
  for (size_t t : texels) {
    // Texels are independent; the colour channels of one texel are not, so
    // the pooled test sums luminance.
    const double se_y = ref.std_error(t, kLuminance) * scale;
    var_sum += se_y * se_y;
    double expected_y = 0;
    for (int c = 0; c < 3; ++c) {
      const Estimate r{ref.mean_of(t, c) * scale, ref.std_error(t, c) * scale,
                       static_cast<double>(ref.samples[t] - 1)};
      const Estimate e{expected[t * 3 + static_cast<size_t>(c)], 0, kKnownVariance};
      const Comparison cmp = compare(r, e);
      a.max_abs_t = std::max(a.max_abs_t, std::abs(cmp.t));
      if (cmp.p_value < alpha) ++a.failures;
      expected_y += e.mean * (c == 0 ? 0.2126 : (c == 1 ? 0.7152 : 0.0722));
    }
    sum_ref += ref.mean_of(t, kLuminance) * scale;
    sum_expected += expected_y;
  }
  a.pooled_ratio = sum_expected > 0 ? sum_ref / sum_expected : 1.0;
  a.pooled_z = var_sum > 0 ? (sum_ref - sum_expected) / std::sqrt(var_sum) : 0.0;
  return a;
}

ReferenceLightmap bake(const scene::Scene& s, int resolution, const ReferenceSettings& settings) {
  auto atlas = atlas::build_atlas(s, {.resolution = resolution});
  EXPECT_TRUE(atlas.is_ok()) << atlas.status().to_string();
  auto ref = bake_reference(s, atlas.value(), settings);
  EXPECT_TRUE(ref.is_ok()) << ref.status().to_string();
  return std::move(ref.value());
}

TEST(AgreementStats, MatchesTabulatedQuantiles) {
  EXPECT_NEAR(two_sided_critical(0.05, kKnownVariance), 1.959964, 1e-5);
  EXPECT_NEAR(two_sided_critical(1e-3, kKnownVariance), 3.290527, 1e-5);
  EXPECT_NEAR(two_sided_critical(0.05, 10), 2.228139, 1e-5);
  EXPECT_NEAR(two_sided_critical(0.01, 5), 4.032143, 1e-5);
  EXPECT_NEAR(two_sided_critical(0.001, 30), 3.645959, 1e-5);
  EXPECT_NEAR(two_sided_p(2.228139, 10), 0.05, 1e-6);
  EXPECT_NEAR(sidak_alpha(0.05, 1), 0.05, 1e-15);
  EXPECT_NEAR(sidak_alpha(1e-3, 1000), 1.0005e-6, 1e-9);
  const Comparison c = compare({1.0, 0.3, 9}, {0.0, 0.4, kKnownVariance});
  EXPECT_NEAR(c.t, 2.0, 1e-12);
  // Welch-Satterthwaite: 0.25^2 / (0.09^2 / 9) = 69.4.
  EXPECT_NEAR(c.dof, 0.0625 / (0.0081 / 9), 1e-9);
}

TEST(ReferenceTracer, FurnaceMatchesGeometricSeries) {
  const Vec3 albedo{0.5f, 0.8f, 0.2f}, emission{1.0f, 0.5f, 0.25f};
  const scene::Scene s = furnace(albedo, emission);
  const ReferenceSettings settings{.samples_per_texel = 256, .max_bounces = 3, .seed = 7};
  const ReferenceLightmap ref = bake(s, 24, settings);
  auto expected_for = [&](int bounces) {
    std::vector<double> e(ref.coverage.size() * 3, 0.0);
    for (size_t t = 0; t < ref.coverage.size(); ++t) {
      for (int c = 0; c < 3; ++c) {
        double series = 0, rho_k = 1;
        for (int k = 0; k <= bounces; ++k, rho_k *= albedo[c]) series += rho_k;
        e[t * 3 + static_cast<size_t>(c)] = kPi * emission[c] * series;
      }
    }
    return e;
  };
  const Agreement ok = check(ref, expected_for(3));
  std::printf("furnace: %zu tests, max |t| %.2f, ratio %.5f (z %.2f), %.2f M paths/s\n", ok.tests,
              ok.max_abs_t, ok.pooled_ratio, ok.pooled_z,
              static_cast<double>(ref.paths) / ref.seconds * 1e-6);
  EXPECT_GT(ok.tests, 300u);
  EXPECT_FALSE(ok.detected()) << "max |t| " << ok.max_abs_t << ", pooled z " << ok.pooled_z;
  // One bounce fewer in the expectation, or 3 % too bright, must be caught.
  EXPECT_TRUE(check(ref, expected_for(2)).detected());
  EXPECT_TRUE(check(ref, expected_for(3), 1.03).detected());
}

TEST(ReferenceTracer, RectangleLightMatchesFormFactor) {
  const RectangleSetup r;
  const Vec3 emission{2.0f, 1.0f, 0.5f};
  const ReferenceSettings settings{.samples_per_texel = 256, .max_bounces = 0, .seed = 11};
  for (bool double_sided : {false, true}) {
    for (float facing : {-1.0f, 1.0f}) {  // -1: towards the floor
      const scene::Scene s = rectangle_over_floor(r, emission, {0, facing, 0}, double_sided);
      auto atlas = atlas::build_atlas(s, {.resolution = 20});
      ASSERT_TRUE(atlas.is_ok()) << atlas.status().to_string();
      auto info = atlas::build_sample_info(s, atlas.value());
      ASSERT_TRUE(info.is_ok()) << info.status().to_string();
      const ReferenceLightmap ref = bake(s, 20, settings);
      const bool lit = double_sided || facing < 0;
      // Expected texel value: the mean of the closed form over the texel's
      // valid sample positions (the texel domain both sides integrate over).
      std::vector<double> expected(ref.coverage.size() * 3, 0.0);
      size_t lit_texels = 0;
      for (uint32_t texel : info.value().covered_texels) {
        const uint32_t off = info.value().offsets[texel];
        const uint32_t n = static_cast<uint32_t>(std::popcount(info.value().words[off]) +
                                                 std::popcount(info.value().words[off + 1]));
        double sum = 0;
        for (uint32_t rank = 0; rank < n; ++rank) {
          const atlas::SamplePoint sp = atlas::sample_point(info.value(), texel, rank);
          if (sp.triangle >= 2) continue;  // the emitter's own texels receive nothing
          const auto& m = s.meshes[0];
          const Vec3 w = atlas::atlas_barycentrics(
              atlas::texel_triangle(s, atlas.value(), sp.instance, sp.triangle), sp.x, sp.y);
          Vec3 p{0, 0, 0};
          for (int k = 0; k < 3; ++k)
            p = p + m.positions[m.indices[sp.triangle * 3 + static_cast<uint32_t>(k)]] * w[k];
          sum += rectangle_irradiance(r, p.x, p.z);
        }
        for (int c = 0; c < 3; ++c)
          expected[size_t{texel} * 3 + static_cast<size_t>(c)] = lit ? emission[c] * sum / n : 0.0;
        if (lit && sum > 0) ++lit_texels;
      }
      const Agreement ok = check(ref, expected);
      std::printf(
          "rectangle (double sided %d, facing %+g): %zu tests, max |t| %.2f, ratio %.5f (z %.2f)\n",
          double_sided, static_cast<double>(facing), ok.tests, ok.max_abs_t, ok.pooled_ratio,
          ok.pooled_z);
      EXPECT_FALSE(ok.detected()) << "max |t| " << ok.max_abs_t << ", pooled z " << ok.pooled_z;
      if (lit) {
        EXPECT_GT(lit_texels, 100u);
        EXPECT_TRUE(check(ref, expected, 1.03).detected()) << "3 % too bright went unnoticed";
      } else {
        for (double v : ref.mean) EXPECT_EQ(v, 0.0);
      }
    }
  }
}

TEST(ReferenceTracer, RefusesWhatItDoesNotModel) {
  scene::Scene s = furnace({0.5f, 0.5f, 0.5f}, {1, 1, 1});
  auto atlas = atlas::build_atlas(s, {.resolution = 8});
  ASSERT_TRUE(atlas.is_ok());
  auto refused = [&](const char* what) {
    auto r = bake_reference(s, atlas.value(), {});
    ASSERT_FALSE(r.is_ok()) << what;
    EXPECT_NE(r.status().message().find(what), std::string::npos) << r.status().to_string();
  };
  s.materials[0].roughness_factor = 0.1f;  // below ReferenceScene::kMinRoughness
  refused("'m0'");
  s.materials[0].roughness_factor = 1;
  s.materials[0].ior = 1.33f;
  refused("'m0'");
  s.materials[0].ior = 1.5f;
  s.lights.push_back(scene::Light{.name = "bulb"});
  refused("'bulb'");
}

// ---- The glTF BRDF (reference_bsdf.h) -------------------------------------

Dir3 direction(double mu) {
  return {std::sqrt(std::max(0.0, 1.0 - mu * mu)), 0.0, mu};
}

// Directional albedo int f(wo, wi) cos(wi) dwi by the midpoint rule on an
// (theta_i, phi_i) grid: a different parameterisation from the table's
// half-vector quadrature. wo lies in the xz plane: phi in [0, pi], twice.
Rgb brute_force_albedo(const GgxBrdf& f, double mu_o, int n_theta = 1024, int n_phi = 512) {
  const Dir3 wo = direction(mu_o);
  const double dt = 0.5 * kPi / n_theta, dp = kPi / n_phi;
  Rgb sum;
  for (int i = 0; i < n_theta; ++i) {
    const double theta = (i + 0.5) * dt, ct = std::cos(theta), st = std::sin(theta);
    Rgb row;
    for (int j = 0; j < n_phi; ++j) {
      const double phi = (j + 0.5) * dp;
      row += f.eval(wo, {st * std::cos(phi), st * std::sin(phi), ct});
    }
    sum += row * (ct * st);
  }
  return sum * (2.0 * dt * dp);
}

// The estimate the tracer's extension rays make: mean of f cos / pdf over
// GgxBrdf::sample (directions below the horizon count 0), with its
// standard error per channel.
void sampled_albedo(const GgxBrdf& f, double mu_o, int n, uint64_t seed, Rgb* mean, Rgb* se) {
  const Dir3 wo = direction(mu_o);
  Pcg32 rng(seed, 3);
  double s1[3] = {0, 0, 0}, s2[3] = {0, 0, 0};
  for (int k = 0; k < n; ++k) {
    const double uc = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
    const Dir3 wi = f.sample(wo, uc, u1, u2);
    if (wi.z <= 0) continue;
    const double pdf = f.pdf(wo, wi);
    ASSERT_GT(pdf, 0.0);
    const Rgb w = f.eval(wo, wi) * (wi.z / pdf);
    for (int c = 0; c < 3; ++c) {
      s1[c] += w[c];
      s2[c] += w[c] * w[c];
    }
  }
  double m[3], e[3];
  for (int c = 0; c < 3; ++c) {
    m[c] = s1[c] / n;
    e[c] = std::sqrt(std::max(0.0, s2[c] / n - m[c] * m[c]) / (n - 1));
  }
  *mean = {m[0], m[1], m[2]};
  *se = {e[0], e[1], e[2]};
}

GgxBrdf white_metal(const GgxAlbedo& table, BrdfModel model) {
  return {Rgb::gray(1.0), 1.0, table.roughness(), &table, model};
}

// E(mu): the table (its quadrature, interpolated in sqrt(mu)) against the
// brute-force albedo of single-scattering GGX with F = 1. The midpoint rule
// needs a finer grid towards grazing wo (the lobe hugs the horizon there).
TEST(ReferenceBsdf, AlbedoTableMatchesBruteForceIntegral) {
  double worst = 0;
  for (double roughness : {0.3, 0.4, 0.5, 0.8, 1.0}) {
    const GgxAlbedo table(roughness);
    const GgxBrdf f = white_metal(table, BrdfModel::kNoCompensation);
    for (double mu : {0.03, 0.1, 0.3, 0.55, 0.9, 1.0}) {
      const double brute =
          mu < 0.1 ? brute_force_albedo(f, mu, 4096, 2048)[0] : brute_force_albedo(f, mu)[0];
      const double quad = GgxAlbedo::quadrature(mu, roughness * roughness);
      worst = std::max({worst, std::abs(table(mu) - brute), std::abs(quad - brute)});
      EXPECT_NEAR(quad, brute, 2e-4) << "roughness " << roughness << " mu " << mu;
      EXPECT_NEAR(table(mu), brute, 2e-4) << "roughness " << roughness << " mu " << mu;
    }
    // E_avg = 2 int E mu dmu = 4 int E(x^2) x^3 dx, here by a 24-point
    // Gauss-Legendre rule on the quadrature itself (not the table).
    double avg = 0;
    constexpr int kN = 24;
    for (int i = 0; i < kN; ++i) {
      // Gauss-Legendre on [0, 1] by Newton on P_n, as in any textbook.
      double z = std::cos(kPi * (i + 0.75) / (kN + 0.5)), dp = 0;
      for (int it = 0; it < 100; ++it) {
        double p0 = 1, p1 = 0;
        for (int k = 1; k <= kN; ++k) {
          const double p2 = p1;
          p1 = p0;
          p0 = ((2.0 * k - 1) * z * p1 - (k - 1.0) * p2) / k;
        }
        dp = kN * (z * p0 - p1) / (z * z - 1);
        z -= p0 / dp;
      }
      const double x = 0.5 * (1 - z), w = 1.0 / ((1 - z * z) * dp * dp);
      avg += w * 4.0 * GgxAlbedo::quadrature(x * x, roughness * roughness) * x * x * x;
    }
    EXPECT_NEAR(table.average(), avg, 2e-4) << "roughness " << roughness;
    EXPECT_LT(table.average(), 1.0);
    std::printf("roughness %.1f: E_avg %.5f (Gauss-Legendre %.5f), E(1) %.5f, E(0.1) %.5f\n",
                roughness, table.average(), avg, table(1.0), table(0.1));
  }
  std::printf("largest |table or quadrature - brute force|: %.2e\n", worst);
}

// With the compensation, a white metal (F = 1) reflects exactly 1 in every
// direction; without it, E(mu).
TEST(ReferenceBsdf, WhiteMetalAlbedoIsOneWithCompensation) {
  for (double roughness : {0.3, 0.5, 1.0}) {
    const GgxAlbedo table(roughness);
    for (double mu : {0.1, 0.3, 0.7, 1.0}) {
      const Rgb with = brute_force_albedo(white_metal(table, BrdfModel::kGltf), mu);
      const Rgb without = brute_force_albedo(white_metal(table, BrdfModel::kNoCompensation), mu);
      EXPECT_NEAR(with[0], 1.0, 5e-4) << "roughness " << roughness << " mu " << mu;
      EXPECT_NEAR(without[0], table(mu), 2e-4) << "roughness " << roughness << " mu " << mu;
    }
  }
}

// The sampled estimate (what the tracer's extension rays do) against the
// brute-force albedo of the same BRDF, for the materials of the agreement
// test and the injected-error models.
TEST(ReferenceBsdf, SampledAlbedoMatchesBruteForceIntegral) {
  struct Case {
    Rgb base;
    double metallic, roughness;
    BrdfModel model;
  };
  const Rgb gold{1.0, 0.71, 0.29}, red{0.63, 0.065, 0.05};
  const Case cases[] = {{gold, 1.0, 0.4, BrdfModel::kGltf},
                        {red, 0.0, 0.5, BrdfModel::kGltf},
                        {Rgb::gray(0.725), 0.0, 0.8, BrdfModel::kGltf},
                        {Rgb::gray(0.8), 0.0, 0.3, BrdfModel::kGltf},
                        {gold, 0.5, 0.6, BrdfModel::kGltf},
                        {gold, 1.0, 0.4, BrdfModel::kNoCompensation},
                        {red, 0.0, 0.5, BrdfModel::kPreviousDiffuseWeight}};
  uint64_t seed = 1;
  for (const Case& k : cases) {
    const GgxAlbedo table(k.roughness);
    const GgxBrdf f{k.base, k.metallic, k.roughness, &table, k.model};
    for (double mu : {0.9, 0.4, 0.1}) {
      const Rgb brute = brute_force_albedo(f, mu);
      Rgb mean, se;
      sampled_albedo(f, mu, 1 << 18, seed++, &mean, &se);
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(mean[c], brute[c], 5 * se[c] + 1e-4)
            << "base " << k.base[c] << " metallic " << k.metallic << " roughness " << k.roughness
            << " model " << static_cast<int>(k.model) << " mu " << mu << " channel " << c;
    }
  }
}

// The white-metal furnace: every facet emits L_e and is a white metal
// (base 1, metallic 1: F = 1), so with the compensation E = pi L_e (B + 1)
// exactly; the reference without compensation (single scattering) must be
// rejected, as must one bounce too few.
TEST(ReferenceTracer, WhiteMetalFurnaceMatchesClosedForm) {
  const Vec3 emission{1.0f, 0.5f, 0.25f};
  constexpr int kBounces = 3;
  for (float roughness : {0.5f, 1.0f}) {
    const scene::Scene s = furnace({1, 1, 1}, emission, 1.0f, roughness);
    ReferenceSettings settings{.samples_per_texel = 256, .max_bounces = kBounces, .seed = 5};
    const ReferenceLightmap ref = bake(s, 24, settings);
    auto expected_for = [&](int bounces) {
      std::vector<double> e(ref.coverage.size() * 3, 0.0);
      for (size_t t = 0; t < ref.coverage.size(); ++t)
        for (int c = 0; c < 3; ++c)
          e[t * 3 + static_cast<size_t>(c)] = kPi * emission[c] * (bounces + 1);
      return e;
    };
    const Agreement ok = check(ref, expected_for(kBounces));
    settings.brdf = BrdfModel::kNoCompensation;
    const Agreement single = check(bake(s, 24, settings), expected_for(kBounces));
    std::printf(
        "white metal furnace, roughness %.1f: %zu tests, max |t| %.2f, ratio %.5f (z %.2f); "
        "without compensation ratio %.5f (z %.1f); %.2f M paths/s\n",
        static_cast<double>(roughness), ok.tests, ok.max_abs_t, ok.pooled_ratio, ok.pooled_z,
        single.pooled_ratio, single.pooled_z, static_cast<double>(ref.paths) / ref.seconds * 1e-6);
    EXPECT_GT(ok.tests, 300u);
    EXPECT_FALSE(ok.detected()) << "max |t| " << ok.max_abs_t << ", pooled z " << ok.pooled_z;
    EXPECT_TRUE(check(ref, expected_for(kBounces - 1)).detected());
    EXPECT_TRUE(single.detected());
  }
}

}  // namespace
}  // namespace luxel::reference
