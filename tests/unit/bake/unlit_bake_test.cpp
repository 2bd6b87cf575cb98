// KHR_materials_unlit in a real bake: the importer turns an unlit material
// into a Lambertian surface of albedo base colour (scene/materials.cpp), so
// a scene with an unlit floor must bake the same lightmap as the same scene
// with a Lambert floor of that base colour, within Monte Carlo noise. The
// floor's own texels show that an unlit surface still receives a lightmap;
// a wall beside it receives light that bounced off the floor, which is
// where the floor's albedo shows. The two bakes use different seeds, so the
// comparison is statistical (two-sample z-tests per texel, Šidák-corrected,
// plus the pooled mean ratio), and an injected 20 % error in the reference's
// base colour must make it fail.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include "bake/bake.h"
#include "scene/gltf_import.h"
#include "support/device_context.h"
#include "support/test_scenes.h"

namespace luxel {
namespace {

constexpr float kBase[3] = {0.8f, 0.55f, 0.3f};

// The floor's material as the importer makes it from a file: material 0 is
// the unlit one, material 1 a core metallic-roughness Lambert (metallic 0,
// roughness 1) of base colour kBase * scale.
std::array<scene::Material, 2> imported_floor_materials(float scale) {
  char json[1024];
  std::snprintf(json, sizeof json,
                R"({"asset": {"version": "2.0"},
                    "extensionsUsed": ["KHR_materials_unlit"],
                    "materials": [
                      {"name": "unlit",
                       "pbrMetallicRoughness": {"baseColorFactor": [%g, %g, %g, 1],
                                                "metallicFactor": 1, "roughnessFactor": 0.2},
                       "emissiveFactor": [1, 1, 1],
                       "extensions": {"KHR_materials_unlit": {}}},
                      {"name": "lambert",
                       "pbrMetallicRoughness": {"baseColorFactor": [%g, %g, %g, 1],
                                                "metallicFactor": 0, "roughnessFactor": 1}}]})",
                kBase[0], kBase[1], kBase[2], kBase[0] * scale, kBase[1] * scale, kBase[2] * scale);
  auto r = scene::import_gltf_memory(json, "", "floor_materials.gltf");
  EXPECT_TRUE(r) << r.status().to_string();
  if (!r || r->materials.size() < 2) return {};
  EXPECT_TRUE(r->import_stats.warnings.empty());
  return {r->materials[0], r->materials[1]};
}

// A 2 x 2 floor (y = 0, facing +y; atlas left half) and a 2 x 2 wall at
// x = 1 facing -x (grey Lambert 0.5; atlas right half), under a constant sky.
scene::Scene floor_and_wall(const scene::Material& floor) {
  scene::Scene s;
  s.source_name = "floor_and_wall";
  s.materials.push_back(floor);
  s.materials.push_back(testing::diffuse_material(0.5f));
  const float m = 0.02f;
  testing::add_quad(s, {-1, 0, -1}, {0, 0, 2}, {2, 0, 0}, m, m, 0.5f - m, 1 - m, 0);
  testing::add_quad(s, {1, 0, -1}, {0, 0, 2}, {0, 2, 0}, 0.5f + m, m, 1 - m, 1 - m, 1);
  return s;
}

struct Comparison {
  size_t texels = 0, wall_texels = 0;
  double max_z = 0, bound = 0;
  double wall_ratio = 0, wall_ratio_z = 0;  // pooled mean of test / reference - 1 on the wall
  bool ok() const { return max_z <= bound && std::fabs(wall_ratio_z) <= 4.0; }
};

// Two independent bakes of the same expected lightmap: per texel and
// channel, z = (a - b) / sqrt(se_a^2 + se_b^2) with each bake's own
// standard error (its relative error times the value), Šidák-corrected over
// all tests at family alpha 1e-3; and the wall's mean ratio with its sample
// confidence interval (|z| <= 4).
Comparison compare(const pipeline::BakeResult& a, const pipeline::BakeResult& b) {
  Comparison c;
  std::vector<double> ratios;
  std::vector<double> zs;
  const int w = a.width;
  for (size_t t = 0; t < size_t(a.width) * a.height; ++t) {
    if (a.irradiance[t * 4 + 3] < 1.0f || b.irradiance[t * 4 + 3] < 1.0f) continue;
    if (a.samples[t] < 2 || b.samples[t] < 2) continue;
    ++c.texels;
    for (size_t ch = 0; ch < 3; ++ch) {
      const double x = a.irradiance[t * 4 + ch], y = b.irradiance[t * 4 + ch];
      const double se = std::hypot(a.rel_error[t] * x, b.rel_error[t] * y) + 1e-6 * (x + y);
      zs.push_back(std::fabs(x - y) / se);
    }
    if (static_cast<int>(t % static_cast<size_t>(w)) >= w / 2) {
      ++c.wall_texels;
      ratios.push_back(a.irradiance[t * 4 + 1] / b.irradiance[t * 4 + 1] - 1.0);
    }
  }
  const double per_test = 1.0 - std::pow(1.0 - 1e-3, 1.0 / std::max<size_t>(zs.size(), 1));
  double lo = 0, hi = 40;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (std::erfc(mid / std::sqrt(2.0)) > per_test ? lo : hi) = mid;
  }
  c.bound = hi;
  for (double z : zs) c.max_z = std::max(c.max_z, z);
  double mean = 0, var = 0;
  for (double r : ratios) mean += r;
  mean /= std::max<size_t>(ratios.size(), 1);
  for (double r : ratios) var += (r - mean) * (r - mean);
  var /= std::max<size_t>(ratios.size(), 2) - 1;
  c.wall_ratio = 1 + mean;
  c.wall_ratio_z = mean / (std::sqrt(var / std::max<size_t>(ratios.size(), 1)) + 1e-6);
  std::printf("  %zu texels (%zu wall), max |z| %.2f (bound %.2f), wall mean ratio %.4f (z %.2f)\n",
              c.texels, c.wall_texels, c.max_z, c.bound, c.wall_ratio, c.wall_ratio_z);
  return c;
}

class UnlitBakeTest : public testing::DeviceTest<> {
 protected:
  pipeline::BakeResult bake(const scene::Scene& s, uint32_t seed) {
    pipeline::BakeSettings st;
    st.atlas.resolution = 16;
    st.samples_per_texel = 512;
    st.max_bounces = 3;
    st.paths_per_iteration = 1u << 16;
    st.seed = seed;
    st.lights.sky.kind = pipeline::SkySettings::Kind::kConstant;
    st.lights.sky.color = {1.0f, 1.0f, 1.0f};
    st.lights.sky.intensity = 1.0f;
    auto r = pipeline::bake(s, st, *ctx_);
    EXPECT_TRUE(r) << r.status().to_string();
    if (!r) return {};
    return std::move(r.value());
  }
};

TEST_F(UnlitBakeTest, UnlitFloorBakesLikeLambertOfItsBaseColour) {
  const auto same = imported_floor_materials(1.0f);
  const auto off = imported_floor_materials(0.8f);  // injected error: albedo 20 % low
  const pipeline::BakeResult unlit = bake(floor_and_wall(same[0]), 7);
  const pipeline::BakeResult lambert = bake(floor_and_wall(same[1]), 8);
  const pipeline::BakeResult darker = bake(floor_and_wall(off[1]), 8);
  ASSERT_GT(unlit.covered_texels, 150u) << "the unlit floor and the wall both get texels";
  // The floor's own texels are covered: an unlit surface still gets a lightmap.
  size_t floor_covered = 0;
  for (size_t t = 0; t < size_t(unlit.width) * unlit.height; ++t)
    if (static_cast<int>(t % size_t(unlit.width)) < unlit.width / 2 &&
        unlit.irradiance[t * 4 + 3] >= 1.0f && unlit.irradiance[t * 4 + 1] > 0)
      ++floor_covered;
  EXPECT_GT(floor_covered, 80u);

  const Comparison c = compare(unlit, lambert);
  EXPECT_TRUE(c.ok());
  EXPECT_GT(c.wall_texels, 60u);
  const Comparison bad = compare(unlit, darker);
  EXPECT_FALSE(bad.ok()) << "a 20 % error in the floor's albedo must be detected";
  EXPECT_GT(bad.wall_ratio, 1.0) << "the unlit floor reflects more than the darker one";
}

}  // namespace
}  // namespace luxel
