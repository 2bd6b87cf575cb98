// Light probes against closed forms and the lightmap (docs/accuracy.md
// "Light probes"):
//  - a uniform sky: radiance L from every direction, so c_00 = L sqrt(4 pi)
//    and every L1/L2 coefficient is 0; the scalar irradiance is 4 pi L;
//  - a point light of intensity I at distance r in direction w: the probe's
//    radiance is a delta, c_lm = (I / r^2) Y_lm(w) exactly, and the L2
//    irradiance is the SH projection of the clamped cosine lobe about w;
//  - the furnace box: radiance Le / (1 - a) everywhere, so E(n) = pi L for
//    every n, the lightmap furnace's value;
//  - a probe just above a lit plane and the lightmap texel under it see the
//    same irradiance about the plane's normal (the signal is a hemispherical
//    step about that normal: odd bands > 1 do not reach irradiance, so L2 is
//    exact);
//  - a probe inside a closed cube is detected (flagged, or moved by the
//    adaptive mode); a sealed two-room box measures light leaking through the
//    partition in the SDK's interpolation with and without visibility.
// Probe estimates are independent, so each statistic is a mean over probes
// with the standard error of that mean (z-test); each check also fails
// with a deliberate 2 % error in the expected value.
// Over 500 lines: placement, the probe bake against closed forms and the
// lightmap, the files and the SDK query share one set of scenes.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <nlohmann/json.hpp>

#include "bake/bake.h"
#include "device/context.h"
#include "kernels/shared/bases.h"
#include "luxel_lightmap.h"
#include "probes/gltf_nodes.h"
#include "probes/probe_bake.h"
#include "probes/probe_file.h"
#include "support/device_context.h"
#include "support/test_scenes.h"

namespace luxel {
namespace {

class ProbeTest : public testing::DeviceTest<> {
 protected:
  static pipeline::BakeSettings settings(uint32_t spp, int bounces) {
    pipeline::BakeSettings s;
    s.samples_per_texel = spp;
    s.max_bounces = bounces;
    s.paths_per_iteration = 1u << 16;
    s.seed = 7;
    return s;
  }
  static probes::ProbeBake bake(const scene::Scene& s, const pipeline::BakeSettings& st,
                                const probes::ProbeBakeSettings& p) {
    auto r = probes::bake_probes(s, st, p, *ctx_);
    EXPECT_TRUE(r) << r.status().to_string();
    return r ? std::move(r.value()) : probes::ProbeBake{};
  }
};

struct MeanTest {
  double mean_ratio = 0, z = 0, mean_d = 0, se = 0;
};
// z of the mean over n items of value(i) - expected(i); abs_floor bounds
// the standard error from below where the estimator is exact.
MeanTest mean_test(size_t n, const std::function<double(size_t)>& value,
                   const std::function<double(size_t)>& expected, double abs_floor = 1e-7) {
  double sum_d = 0, sum_d2 = 0, sum_e = 0;
  for (size_t t = 0; t < n; ++t) {
    const double d = value(t) - expected(t);
    sum_d += d;
    sum_d2 += d * d;
    sum_e += expected(t);
  }
  const double nn = static_cast<double>(n);
  const double mean_d = sum_d / nn;
  const double var = std::max(0.0, sum_d2 / nn - mean_d * mean_d) * nn / (nn - 1);
  MeanTest m;
  m.se = std::sqrt(var / nn) + abs_floor + 1e-6 * std::fabs(sum_e / nn);
  m.mean_ratio = sum_e != 0 ? 1.0 + sum_d / sum_e : 0.0;
  m.mean_d = mean_d;
  m.z = mean_d / m.se;
  return m;
}

// A speck of black geometry far away: the scene needs a triangle, the sky
// must stay (almost) unoccluded (solid angle ~1e-10 sr).
scene::Scene sky_only() {
  scene::Scene s;
  s.source_name = "sky_only";
  s.materials.push_back(testing::diffuse_material(0.0f));
  testing::add_quad(s, {100, -100, 100}, {1e-3f, 0, 0}, {0, 0, 1e-3f}, 0, 0, 1, 1, 0);
  return s;
}

std::string positions_json(const std::vector<Vec3>& p) {
  std::string j = "[";
  for (size_t i = 0; i < p.size(); ++i)
    j += strprintf("%s[%g,%g,%g]", i ? "," : "", double(p[i].x), double(p[i].y), double(p[i].z));
  return j + "]";
}

probes::ProbeBakeSettings file_probes(const std::vector<Vec3>& p) {
  probes::ProbeBakeSettings ps;
  ps.placement.mode = probes::PlacementMode::kFile;
  ps.placement.file = "test.json";
  ps.placement.file_contents = positions_json(p);
  return ps;
}

std::vector<Vec3> scatter(size_t n, Vec3 lo, Vec3 hi) {
  std::vector<Vec3> out;
  for (size_t i = 0; i < n; ++i) {
    const double a = std::fmod(0.7548776662 * (i + 1), 1.0),
                 b = std::fmod(0.5698402910 * (i + 1), 1.0),
                 c = std::fmod(0.6180339887 * (i + 1), 1.0);
    out.push_back(
        lo + Vec3{float(a) * (hi.x - lo.x), float(b) * (hi.y - lo.y), float(c) * (hi.z - lo.z)});
  }
  return out;
}

TEST(ProbeSpec, ParsesEveryModeAndNamesTheField) {
  auto g = probes::parse_probe_spec("grid:0.5");
  ASSERT_TRUE(g);
  EXPECT_EQ(g.value().mode, probes::PlacementMode::kGrid);
  EXPECT_FLOAT_EQ(g.value().spacing, 0.5f);
  auto b = probes::parse_probe_spec("grid:0.25:box=-1,0,-1,1,2,1");
  ASSERT_TRUE(b);
  EXPECT_TRUE(b.value().has_box);
  EXPECT_FLOAT_EQ(b.value().box.hi.y, 2.0f);
  EXPECT_EQ(probes::describe_probe_spec(b.value()), "grid:0.25:box=-1,0,-1,1,2,1");
  auto f = probes::parse_probe_spec("file:P.json");
  ASSERT_TRUE(f);
  EXPECT_EQ(f.value().file, "P.json");
  EXPECT_EQ(probes::parse_probe_spec("adaptive:1").value().mode, probes::PlacementMode::kAdaptive);
  for (const char* bad : {"grid", "grid:0", "grid:-1", "grid:x", "cube:1", "grid:1:box=1,2",
                          "file:", "grid:1:foo=2"}) {
    auto r = probes::parse_probe_spec(bad);
    ASSERT_FALSE(r) << bad;
    EXPECT_NE(r.status().message().find("settings.probes"), std::string::npos) << bad;
  }
}

TEST(ProbeNodes, TaggedGltfNodesGiveWorldPositions) {
  // Parent translated by (1, 0, 0) and rotated 90 degrees about +z; its
  // tagged child at local (0, 2, 0) lands at (1, 0, 0) + Rz(90)(0, 2, 0) =
  // (-1, 0, 0); a tagged node given by matrix; an untagged node.
  const double h = std::sqrt(0.5);
  const std::string gltf = strprintf(
      R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0,2,3]}],"nodes":[
      {"translation":[1,0,0],"rotation":[0,0,%.17g,%.17g],"children":[1]},
      {"translation":[0,2,0],"extras":{"luxelProbe":true}},
      {"matrix":[1,0,0,0, 0,1,0,0, 0,0,1,0, 3,4,5,1],"extras":{"luxelProbe":true}},
      {"translation":[9,9,9],"extras":{"luxelProbe":false}}]})",
      h, h);
  auto j = probes::probe_nodes_json(gltf);
  ASSERT_TRUE(j) << j.status().to_string();
  const auto list = nlohmann::json::parse(j.value());
  ASSERT_EQ(list.size(), 2u) << j.value();
  // Depth-first from the last root: the matrix node, then the child.
  EXPECT_NEAR(list[0][0].get<double>(), 3, 1e-9);
  EXPECT_NEAR(list[0][2].get<double>(), 5, 1e-9);
  EXPECT_NEAR(list[1][0].get<double>(), -1, 1e-9);
  EXPECT_NEAR(list[1][1].get<double>(), 0, 1e-9);
  EXPECT_NEAR(list[1][2].get<double>(), 0, 1e-9);
  EXPECT_FALSE(probes::probe_nodes_json(R"({"scenes":[{"nodes":[0]}],"nodes":[{}]})"));
  EXPECT_FALSE(probes::probe_nodes_json("not json"));
  EXPECT_EQ(probes::parse_probe_spec("nodes").value().mode, probes::PlacementMode::kNodes);
}

TEST(ShWindow, SigmaFactorsFollowSloan) {
  const auto h = probes::sh_window_sigma(probes::ShWindow::kHanning, 3);
  EXPECT_NEAR(h[1], 0.75, 1e-6);
  EXPECT_NEAR(h[2], 0.25, 1e-6);
  const auto l = probes::sh_window_sigma(probes::ShWindow::kLanczos, 3);
  EXPECT_NEAR(l[1], std::sin(M_PI / 3) / (M_PI / 3), 1e-6);
  EXPECT_NEAR(l[2], std::sin(2 * M_PI / 3) / (2 * M_PI / 3), 1e-6);
  EXPECT_EQ(probes::sh_window_sigma(probes::ShWindow::kNone, 3)[2], 1.0f);
}

TEST_F(ProbeTest, UniformSkyGivesExactShMoments) {
  const scene::Scene s = sky_only();
  auto st = settings(2048, 2);
  st.lights.sky.kind = pipeline::SkySettings::Kind::kConstant;
  st.lights.sky.color = {1, 1, 1};
  st.lights.sky.intensity = 1.5f;
  const float L = 1.5f;
  const auto p = scatter(48, {-2, -2, -2}, {2, 2, 2});
  const probes::ProbeBake b = bake(s, st, file_probes(p));
  ASSERT_EQ(b.count(), p.size());
  EXPECT_EQ(b.sh_count, 9);
  const double c00 = L * std::sqrt(4 * M_PI);
  const MeanTest m0 = mean_test(
      b.count(), [&](size_t i) { return double(b.sh(i)[0]); }, [&](size_t) { return c00; });
  std::printf("  sky c00 ratio %.5f z %.2f\n", m0.mean_ratio, m0.z);
  EXPECT_LT(std::fabs(m0.z), 4.5);
  EXPECT_GT(std::fabs(mean_test(
                          b.count(), [&](size_t i) { return double(b.sh(i)[0]); },
                          [&](size_t) { return c00 * 1.02; })
                          .z),
            4.5)
      << "the c00 check must fail with a 2 % error";
  for (int k = 1; k < 9; ++k) {
    const MeanTest mk = mean_test(
        b.count(), [&](size_t i) { return double(b.sh(i)[k * 3 + 1]); },
        [](size_t) { return 0.0; });
    std::printf("  sky c%d mean %.5f (se %.5f) z %.2f\n", k, mk.mean_d, mk.se, mk.z);
    EXPECT_LT(std::fabs(mk.z), 4.5) << "coefficient " << k;
    // A 2 % of c00 leak into band k must be seen.
    EXPECT_GT(std::fabs(mean_test(
                            b.count(), [&](size_t i) { return double(b.sh(i)[k * 3 + 1]); },
                            [&](size_t) { return 0.02 * c00; })
                            .z),
              4.5);
  }
  // Scalar irradiance (integral of L over the sphere) 4 pi L.
  const MeanTest e = mean_test(
      b.count(), [&](size_t i) { return double(b.bake.irradiance[i * 4]); },
      [&](size_t) { return 4 * M_PI * L; });
  std::printf("  sky scalar irradiance ratio %.5f z %.2f, error estimate %.4f\n", e.mean_ratio, e.z,
              b.bake.error);
  EXPECT_LT(std::fabs(e.z), 4.5);
  EXPECT_EQ(b.negative_raw, 0.0);
}

TEST_F(ProbeTest, PointLightGivesTheShOfItsDirection) {
  const scene::Scene base = sky_only();
  scene::Scene s = base;
  scene::Light light;
  light.type = scene::LightType::kPoint;
  light.intensity = 2.0f;
  light.position = {0.3f, 1.1f, -0.4f};
  s.lights.push_back(light);
  const auto p = scatter(48, {-1.5f, -1.5f, -1.5f}, {1.5f, -0.2f, 1.5f});
  const probes::ProbeBake b = bake(s, settings(512, 1), file_probes(p));
  ASSERT_EQ(b.count(), p.size());
  auto expected = [&](size_t i, int k) {
    const Vec3 d = light.position - p[i];
    const double r2 = dot(d, d), r = std::sqrt(r2);
    float y[9];
    lux_sh_eval(float(d.x / r), float(d.y / r), float(d.z / r), 9, y);
    return light.intensity / r2 * y[k];
  };
  for (int k = 0; k < 9; ++k) {
    const MeanTest m = mean_test(
        b.count(), [&](size_t i) { return double(b.sh(i)[k * 3]); },
        [&](size_t i) { return expected(i, k); });
    const MeanTest off = mean_test(
        b.count(), [&](size_t i) { return double(b.sh(i)[k * 3]); },
        [&](size_t i) { return expected(i, k) + 0.02 * expected(i, 0); });
    std::printf("  point c%d ratio %.5f z %.2f (2 %% injected: z %.1f)\n", k, m.mean_ratio, m.z,
                off.z);
    EXPECT_LT(std::fabs(m.z), 4.5) << "coefficient " << k;
    EXPECT_GT(std::fabs(off.z), 4.5) << "coefficient " << k << ": injected error not seen";
  }
  // The L2 irradiance about n is the SH projection of the clamped cosine
  // lobe about the light direction: sum_l A_l (2l+1)/(4 pi) P_l(n.w) I/r^2.
  // Raw, it goes negative away from the light (ringing: its minimum is
  // -0.040 I/r^2 at n.w = -0.53). Hanning of width 3 shrinks the negative
  // region; a Hanning window narrower than 2 (sigma_2 = 0, sigma_1 < 1/2)
  // is non-negative for a delta, hence for any non-negative radiance.
  const double narrow = probes::negative_irradiance_fraction(
      b, probes::sh_window_sigma(probes::ShWindow::kHanning, 1.95f));
  std::printf(
      "  point light: negative irradiance raw %.4f, hanning(3) %.4f, hanning(1.95) %.4f "
      "of (probe, normal)\n",
      b.negative_raw, b.negative_windowed, narrow);
  EXPECT_GT(b.negative_raw, 0.0);
  EXPECT_LT(b.negative_windowed, b.negative_raw);
  EXPECT_EQ(narrow, 0.0);
}

TEST_F(ProbeTest, ProbeFurnaceAgreesWithLightmapFurnace) {
  const float a = 0.3f, le = 1.0f;
  const scene::Scene s = testing::furnace_box(a, le);
  auto st = settings(1024, 12);
  probes::ProbeBakeSettings ps;
  ps.placement = probes::parse_probe_spec("grid:0.5:box=-0.75,-0.75,-0.75,0.75,0.75,0.75").value();
  const probes::ProbeBake b = bake(s, st, ps);
  ASSERT_EQ(b.count(), 64u);
  EXPECT_EQ(b.layout.flagged_inside, 0u) << "probes in an open room are not inside";
  const double L = le / (1 - a);
  const MeanTest c = mean_test(
      b.count(), [&](size_t i) { return double(b.sh(i)[0]); },
      [&](size_t) { return L * std::sqrt(4 * M_PI); });
  std::printf("  furnace probe c00 ratio %.5f z %.2f\n", c.mean_ratio, c.z);
  EXPECT_LT(std::fabs(c.z), 4.5);
  EXPECT_GT(std::fabs(mean_test(
                          b.count(), [&](size_t i) { return double(b.sh(i)[0]); },
                          [&](size_t) { return 1.02 * L * std::sqrt(4 * M_PI); })
                          .z),
            4.5);
  // The lightmap furnace of the same box: irradiance pi L on every wall.
  auto lm_settings = settings(256, 12);
  lm_settings.atlas.resolution = 16;
  auto lm = pipeline::bake(s, lm_settings, *ctx_);
  ASSERT_TRUE(lm) << lm.status().to_string();
  std::vector<size_t> texels;
  for (size_t t = 0; t < size_t(lm.value().width) * lm.value().height; ++t)
    if (lm.value().irradiance[t * 4 + 3] >= 1.0f) texels.push_back(t);
  ASSERT_GT(texels.size(), 100u);
  double lm_sum = 0, lm_sq = 0;
  for (size_t t : texels) {
    lm_sum += lm.value().irradiance[t * 4];
    lm_sq += double(lm.value().irradiance[t * 4]) * lm.value().irradiance[t * 4];
  }
  const double nt = double(texels.size()), lm_mean = lm_sum / nt;
  const double lm_se = std::sqrt(std::max(0.0, lm_sq / nt - lm_mean * lm_mean) / (nt - 1));
  // Probe irradiance about +x (any normal: the field is isotropic).
  double pr_sum = 0, pr_sq = 0;
  for (size_t i = 0; i < b.count(); ++i) {
    float e[3];
    probes::sh_irradiance(b.sh(i), b.sh_count, {1, 1, 1}, 1, 0, 0, e);
    pr_sum += e[0];
    pr_sq += double(e[0]) * e[0];
  }
  const double np = double(b.count()), pr_mean = pr_sum / np;
  const double pr_se = std::sqrt(std::max(0.0, pr_sq / np - pr_mean * pr_mean) / (np - 1));
  const double z = (pr_mean - lm_mean) / std::sqrt(pr_se * pr_se + lm_se * lm_se + 1e-12);
  std::printf("  furnace: probe E %.5f (se %.5f) lightmap E %.5f (se %.5f) (pi L %.5f), z %.2f\n",
              pr_mean, pr_se, lm_mean, lm_se, M_PI * L, z);
  EXPECT_LT(std::fabs(z), 4.5);
  const double z_off =
      (1.02 * pr_mean - lm_mean) / std::sqrt(pr_se * pr_se + lm_se * lm_se + 1e-12);
  EXPECT_GT(std::fabs(z_off), 4.5) << "a 2 % error between the two must be seen";
}

TEST_F(ProbeTest, ProbeAndLightmapTexelAgreeAboveALitPlane) {
  const scene::Scene s = testing::open_plane(0.5f);
  auto st = settings(1024, 3);
  st.lights.sky.kind = pipeline::SkySettings::Kind::kConstant;
  st.lights.sky.color = {1, 1, 1};
  st.lights.sky.intensity = 1.0f;
  // Lightmap: atlas (u, v) -> world (x, z) = (-1 + 2 v, -1 + 2 u).
  auto lm_settings = st;
  lm_settings.atlas.resolution = 16;
  auto lm = pipeline::bake(s, lm_settings, *ctx_);
  ASSERT_TRUE(lm) << lm.status().to_string();
  std::vector<Vec3> pts;
  std::vector<size_t> texels;
  for (int ty = 4; ty < 12; ++ty)
    for (int tx = 4; tx < 12; ++tx) {
      const float u = (tx + 0.5f) / 16, v = (ty + 0.5f) / 16;
      pts.push_back({-1 + 2 * v, 1e-3f, -1 + 2 * u});
      texels.push_back(size_t(ty) * 16 + size_t(tx));
    }
  const probes::ProbeBake b = bake(s, st, file_probes(pts));
  ASSERT_EQ(b.count(), pts.size());
  // Each pair: probe E(+y) against its texel; the z of the mean difference.
  const MeanTest m = mean_test(
      pts.size(),
      [&](size_t i) {
        float e[3];
        probes::sh_irradiance(b.sh(i), b.sh_count, {1, 1, 1}, 0, 1, 0, e);
        return double(e[1]);
      },
      [&](size_t i) { return double(lm.value().irradiance[texels[i] * 4 + 1]); });
  std::printf("  probe / texel irradiance %.5f z %.2f\n", m.mean_ratio, m.z);
  EXPECT_LT(std::fabs(m.z), 4.5);
  EXPECT_GT(std::fabs(mean_test(
                          pts.size(),
                          [&](size_t i) {
                            float e[3];
                            probes::sh_irradiance(b.sh(i), b.sh_count, {1, 1, 1}, 0, 1, 0, e);
                            return double(e[1]);
                          },
                          [&](size_t i) {
                            return 1.02 * double(lm.value().irradiance[texels[i] * 4 + 1]);
                          })
                          .z),
            4.5)
      << "a 2 % difference between probe and texel must be seen";
  EXPECT_NEAR(m.mean_ratio, 1.0, 0.02);
  // Facing down, the probe sees the plane: pi x radiance a E / pi = a pi L.
  const MeanTest down = mean_test(
      pts.size(),
      [&](size_t i) {
        float e[3];
        probes::sh_irradiance(b.sh(i), b.sh_count, {1, 1, 1}, 0, -1, 0, e);
        return double(e[1]);
      },
      [&](size_t) { return 0.5 * M_PI; });
  std::printf("  probe E(-y) / (a pi L) %.5f z %.2f\n", down.mean_ratio, down.z);
  EXPECT_NEAR(down.mean_ratio, 1.0, 0.03);
}

// Two cubes: a room [-2, 2]^3 (walls facing in) and a closed unit cube at
// the origin (faces out). A probe at the origin is inside the small cube.
scene::Scene room_with_closed_cube() {
  scene::Scene s = testing::furnace_box(0.5f, 0.0f, 2.0f);
  const Vec3 normals[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (const Vec3 n : normals) {  // outward normal n: the face at +0.5 n
    const Vec3 axis = std::fabs(n.y) > 0.5f ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    const Vec3 eu = normalize(cross(n, axis)) * 1.0f;
    const Vec3 ev = normalize(cross(n, eu));  // cross(eu, ev) along +n
    testing::add_quad(s, n * 0.5f - eu * 0.5f - ev * 0.5f, eu, ev, 0, 0, 1, 1, 0);
  }
  return s;
}

TEST_F(ProbeTest, ProbeInsideClosedCubeIsFlaggedOrMovedOut) {
  const scene::Scene s = room_with_closed_cube();
  probes::PlacementSettings f;
  f.mode = probes::PlacementMode::kFile;
  f.file_contents = "[[0,0,0],[1.2,0.3,-1.1],[0.2,0.1,0.1]]";
  auto l = probes::place_probes(s, f);
  ASSERT_TRUE(l) << l.status().to_string();
  EXPECT_EQ(l.value().flags[0] & probes::kProbeInside, probes::kProbeInside);
  EXPECT_EQ(l.value().flags[1] & probes::kProbeInside, 0u);
  EXPECT_EQ(l.value().flags[2] & probes::kProbeInside, probes::kProbeInside);
  EXPECT_EQ(l.value().flagged_inside, 2u);
  // Adaptive: a grid of spacing 1 puts a probe at the origin; it moves out.
  auto a =
      probes::place_probes(s, probes::parse_probe_spec("adaptive:1:box=-1,-1,-1,1,1,1").value());
  ASSERT_TRUE(a) << a.status().to_string();
  const auto& la = a.value();
  EXPECT_EQ(la.inside_detected, 1u);
  EXPECT_EQ(la.moved, 1u);
  EXPECT_EQ(la.flagged_inside, 0u);
  const int32_t centre = la.grid_index[1 + 3 * (1 + 3 * 1)];
  ASSERT_GE(centre, 0);
  const Vec3 q = la.positions[size_t(centre)];
  EXPECT_GT(std::max({std::fabs(q.x), std::fabs(q.y), std::fabs(q.z)}), 0.5f)
      << "moved probe still inside the cube";
  EXPECT_EQ(la.flags[size_t(centre)] & probes::kProbeMoved, probes::kProbeMoved);
}

// A sealed box [-1, 1]^3 split by a thin partition at x = 0 (two faces back
// to back), a point light in the left room: the right room is exactly dark.
scene::Scene two_rooms() {
  scene::Scene s = testing::furnace_box(0.5f, 0.0f, 1.0f);
  testing::add_quad(s, {-1e-3f, -1, -1}, {0, 0, 2}, {0, 2, 0}, 0, 0, 1, 1, 0);  // faces -x
  testing::add_quad(s, {1e-3f, -1, -1}, {0, 2, 0}, {0, 0, 2}, 0, 0, 1, 1, 0);   // faces +x
  scene::Light light;
  light.type = scene::LightType::kPoint;
  light.intensity = 4.0f;
  light.position = {-0.5f, 0.2f, 0.1f};
  s.lights.push_back(light);
  return s;
}

TEST_F(ProbeTest, VisibilityStopsLeaksThroughAThinWall) {
  const scene::Scene s = two_rooms();
  probes::ProbeBakeSettings ps;
  ps.placement = probes::parse_probe_spec("grid:0.5:box=-0.75,-0.75,-0.75,0.75,0.75,0.75").value();
  const probes::ProbeBake b = bake(s, settings(1024, 3), ps);
  ASSERT_EQ(b.count(), 64u);
  EXPECT_EQ(b.layout.flagged_inside, 0u);
  const std::string bin = probes::encode_probe_bin(b);
  LuxelProbeSet set;
  ASSERT_EQ(luxel_probes_parse(bin.data(), bin.size(), &set), 0);
  ASSERT_EQ(set.count, 64u);
  // Shading points of the right room between the partition and its first
  // probe plane, normals facing every axis; the truth is 0 there. The left
  // room's points at the mirrored places give the scale.
  double leak_plain = 0, leak_vis = 0, lit_plain = 0, lit_vis = 0;
  size_t n = 0;
  const Vec3 normals[4] = {{1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  for (float x : {0.05f, 0.12f, 0.2f})
    for (float y : {-0.6f, -0.2f, 0.3f, 0.6f})
      for (float z : {-0.5f, 0.0f, 0.4f})
        for (const Vec3& nn : normals) {
          float e[3];
          luxel_probes_irradiance(&set, x, y, z, nn.x, nn.y, nn.z, 0, e);
          leak_plain += e[1];
          luxel_probes_irradiance(&set, x, y, z, nn.x, nn.y, nn.z, 1, e);
          leak_vis += e[1];
          const Vec3 m{-nn.x, nn.y, nn.z};
          luxel_probes_irradiance(&set, -x, y, z, m.x, m.y, m.z, 0, e);
          lit_plain += e[1];
          luxel_probes_irradiance(&set, -x, y, z, m.x, m.y, m.z, 1, e);
          lit_vis += e[1];
          ++n;
        }
  leak_plain /= n;
  leak_vis /= n;
  lit_plain /= n;
  lit_vis /= n;
  std::printf(
      "  leak into the dark room: %.4f without visibility, %.4f with (lit side %.4f / %.4f)\n",
      leak_plain, leak_vis, lit_plain, lit_vis);
  EXPECT_GT(leak_plain, 0.2 * lit_plain) << "trilinear interpolation alone leaks";
  EXPECT_LT(leak_vis, 0.15 * leak_plain) << "visibility must remove most of the leak";
  EXPECT_GT(lit_vis, 0.7 * lit_plain) << "visibility must keep the lit side lit";

  // SDK query cost (a tiny benchmark).
  const auto t0 = std::chrono::steady_clock::now();
  float acc = 0;
  constexpr int kQueries = 200000;
  for (int i = 0; i < kQueries; ++i) {
    float e[3];
    const float t = float(i) / kQueries;
    luxel_probes_irradiance(&set, -0.7f + 1.4f * t, 0.3f - 0.5f * t, 0.2f, 0, 1, 0, 1, e);
    acc += e[0];
  }
  const double ns =
      std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count() /
      kQueries;
  std::printf("  SDK query with visibility: %.0f ns per query (checksum %g)\n", ns, double(acc));
}

TEST_F(ProbeTest, ProgressiveSolverAndErrorStopRule) {
  // The progressive least-squares solver (Listing 7.1) on the sphere
  // converges to the projection's answer for SH (an orthonormal basis);
  // the target-error rule stops a probe bake as it stops a lightmap.
  const scene::Scene s = sky_only();
  auto st = settings(0, 1);
  st.lights.sky.kind = pipeline::SkySettings::Kind::kConstant;
  st.lights.sky.intensity = 1.0f;
  st.target_error = 0.01;
  st.encodings.solver = pipeline::EncodingSolver::kProgressive;
  const auto p = scatter(32, {-1, -1, -1}, {1, 1, 1});
  const probes::ProbeBake b = bake(s, st, file_probes(p));
  ASSERT_EQ(b.count(), p.size());
  EXPECT_EQ(b.bake.termination, pipeline::Termination::kError);
  EXPECT_LE(b.bake.error, 0.01);
  const MeanTest m = mean_test(
      b.count(), [&](size_t i) { return double(b.sh(i)[0]); },
      [&](size_t) { return std::sqrt(4 * M_PI); });
  std::printf("  progressive c00 ratio %.5f z %.2f after %.0f samples per probe (error %.4f)\n",
              m.mean_ratio, m.z, b.bake.mean_spp, b.bake.error);
  EXPECT_LT(std::fabs(m.z), 4.5);
  EXPECT_GT(std::fabs(mean_test(
                          b.count(), [&](size_t i) { return double(b.sh(i)[0]); },
                          [&](size_t) { return 1.02 * std::sqrt(4 * M_PI); })
                          .z),
            4.5);
}

TEST_F(ProbeTest, ProbeStateBakedInTilesUnderASmallBudget) {
  // 4096 probes x 4.3 KB of state do not fit an 8 MiB budget beside the
  // path buffers: the probes are baked in tiles, one after another, as
  // lightmap texels are (bake/tile_plan.h), and stay right.
  const float a = 0.3f;
  const scene::Scene s = testing::furnace_box(a, 1.0f);
  auto st = settings(32, 8);
  st.paths_per_iteration = 8192;
  st.device_memory_budget_mib = 8;
  probes::ProbeBakeSettings ps;
  ps.placement = probes::parse_probe_spec("grid:0.1:box=-0.75,-0.75,-0.75,0.75,0.75,0.75").value();
  const probes::ProbeBake b = bake(s, st, ps);
  ASSERT_EQ(b.count(), 4096u);
  std::printf("  %zu probes in %zu tiles\n", b.count(), b.bake.tiles);
  EXPECT_GT(b.bake.tiles, 1u);
  EXPECT_EQ(b.bake.min_spp, 32u);
  const MeanTest c = mean_test(
      b.count(), [&](size_t i) { return double(b.sh(i)[0]); },
      [&](size_t) { return std::sqrt(4 * M_PI) / (1 - a); });
  std::printf("  tiled furnace c00 ratio %.5f z %.2f\n", c.mean_ratio, c.z);
  EXPECT_LT(std::fabs(c.z), 4.5);
}

TEST_F(ProbeTest, ProbeFilesRoundTripThroughTheSdk) {
  const scene::Scene s = sky_only();
  auto st = settings(64, 1);
  st.lights.sky.kind = pipeline::SkySettings::Kind::kConstant;
  probes::ProbeBakeSettings ps = file_probes({{0, 0, 0}, {1, 2, 3}});
  ps.basis = "sh1";
  const probes::ProbeBake b = bake(s, st, ps);
  const std::string bin = probes::encode_probe_bin(b);
  LuxelProbeSet set;
  ASSERT_EQ(luxel_probes_parse(bin.data(), bin.size(), &set), 0);
  EXPECT_EQ(set.count, 2u);
  EXPECT_EQ(set.sh_count, 4u);
  EXPECT_EQ(set.is_grid, 0u);
  EXPECT_EQ(luxel_probe_record(&set, 1)[1], 2.0f);
  float e[3], f[3];
  luxel_probe_sh_irradiance(&set, 1, 0, 1, 0, e);
  probes::sh_irradiance(b.sh(1), 4, b.sigma, 0, 1, 0, f);
  EXPECT_FLOAT_EQ(e[0], f[0]);
  EXPECT_NE(luxel_probes_parse(bin.data(), 50, &set), 0);
  // User positions: every probe weighted by 1/d^2; under a uniform sky any
  // point and normal see E = pi L (L = 1 here; L1 noise at 64 samples).
  float g[3];
  EXPECT_GT(luxel_probes_irradiance(&set, 0.5f, 1, 1.5f, 0, 0, 1, 1, g), 0.0f);
  EXPECT_NEAR(g[0], M_PI, 0.1 * M_PI);
  const std::string json = probes::encode_probe_json(b);
  EXPECT_NE(json.find("\"conventions\""), std::string::npos);
  EXPECT_NE(json.find("\"hanning\""), std::string::npos);
}

}  // namespace
}  // namespace luxel
