// build_light_table on hand-made scenes: contents, selection by power
// (thesis §6.3.2), errors that name the culprit, feature flags.
#include "shading/light_table.h"

#include <gtest/gtest.h>

#include <cmath>

#include "shading/color.h"
#include "shading_probe.h"
#include "test_scenes.h"

namespace luxel::pipeline {
namespace {

using test::SceneBuilder;

constexpr double kPi = 3.14159265358979323846;

Bounds3 unit_bounds() {
  Bounds3 b;
  b.extend(Vec3{-1, -1, -1});
  b.extend(Vec3{1, 1, 1});
  return b;
}

int type_of(const cl::LuxLight& l) {
  return LUX_LIGHT_TYPE(l);
}
double pmf(const LightTable& t, size_t i) {
  return double(t.select[i].pmf);
}

Result<LightTable> build(const SceneBuilder& b, const LightSettings& settings = {}) {
  return build_light_table(b.s, b.soup(), settings, unit_bounds());
}

TEST(LightTable, SelectionProbabilityIsProportionalToPower) {
  SceneBuilder b;
  b.add_point({0, 2, 0}, {1, 0.5f, 0.25f}, 10.0f);
  b.add_spot({0, 2, 0}, {0, -1, 0}, {1, 1, 1}, 40.0f, 0.2f, 0.6f);
  b.add_directional({0, -1, 0}, {1, 1, 1}, 3.0f);
  const int glow = b.add_emitter({2, 2, 2});
  b.add_triangles({{0, 1, 0}, {1, 1, 0}, {0, 1, 1}, {0, 1, 0}, {0, 1, 2}, {2, 1, 0}}, glow);
  LightSettings settings;
  settings.sky.kind = SkySettings::Kind::kConstant;
  settings.sky.color = {0.5f, 0.6f, 0.7f};
  settings.sky.intensity = 2.0f;
  auto t = build(b, settings);
  ASSERT_TRUE(t.is_ok()) << t.status().to_string();
  ASSERT_EQ(t->lights.size(), 6u);  // point, spot, directional, 2 triangles, sky

  // Powers from the formulas in light_table.h, computed independently here.
  const double r2 = 3.0;  // bounding sphere radius^2 of [-1,1]^3
  const double expected[6] = {
      4 * kPi * luminance({10, 5, 2.5f}),
      2 * kPi * (1 - std::cos(0.4)) * 40.0,
      3.0 * kPi * r2,
      kPi * 0.5 * 2.0,  // area 0.5, L = 2
      kPi * 2.0 * 2.0,  // area 2
      kPi * luminance({1.0f, 1.2f, 1.4f}) * kPi * r2,
  };
  const int types[6] = {LUX_LIGHT_TYPE_POINT,       LUX_LIGHT_TYPE_SPOT,
                        LUX_LIGHT_TYPE_DIRECTIONAL, LUX_LIGHT_TYPE_TRIANGLE,
                        LUX_LIGHT_TYPE_TRIANGLE,    LUX_LIGHT_TYPE_SKY};
  double total = 0;
  for (double p : expected) total += p;
  EXPECT_NEAR(t->total_power / total, 1.0, 1e-6);
  ASSERT_EQ(t->select.size(), 6u);
  for (size_t i = 0; i < 6; ++i) {
    EXPECT_EQ(type_of(t->lights[i]), types[i]) << i;
    EXPECT_NEAR(pmf(t.value(), i) / (expected[i] / total), 1.0, 1e-5) << "light " << i;
  }
  EXPECT_TRUE(t->has_point && t->has_spot && t->has_directional && t->has_emissive && t->has_sky);
  EXPECT_FALSE(t->sky_is_image);
  EXPECT_EQ(t->sky.kind, LUX_SKY_KIND_CONSTANT);
  EXPECT_EQ(t->sky.light, 5);
  EXPECT_EQ(t->triangle_light, (std::vector<int32_t>{3, 4}));
  EXPECT_EQ(t->bytes(),
            6 * sizeof(cl::LuxLight) + 6 * sizeof(cl::LuxAliasEntry) + 2 * 4 + sizeof(cl::LuxSky));
}

TEST(LightTable, EmissiveTrianglesRecordGeometryFlagsAndTheirWorldTriangle) {
  SceneBuilder b;
  b.add_triangles({{0, 0, 0}, {1, 0, 0}, {0, 0, 1}}, 0);  // not emissive
  const int one_sided = b.add_emitter({1, 2, 3});
  const int two_sided = b.add_emitter({1, 1, 1}, true);
  b.add_triangles({{0, 2, 0}, {2, 2, 0}, {0, 2, 2}}, one_sided);  // winding normal -Y
  Mat4 mirror;
  // y -> -y: the mirror image of a downward-facing emitter faces up, while its
  // raw winding (cross(edge1, edge2)) still says down.
  mirror.at(1, 1) = -1;
  b.add_triangles({{0, 2, 0}, {2, 2, 0}, {0, 2, 2}}, one_sided, mirror);
  b.add_triangles({{0, 3, 0}, {1, 3, 0}, {0, 3, 1}}, two_sided);
  b.s.materials[static_cast<size_t>(one_sided)].emissive_strength = 2;
  auto t = build(b);
  ASSERT_TRUE(t.is_ok()) << t.status().to_string();
  ASSERT_EQ(t->lights.size(), 3u);
  EXPECT_EQ(t->triangle_light, (std::vector<int32_t>{-1, 0, 1, 2}));
  const cl::LuxLight& l = t->lights[0];
  EXPECT_EQ(LUX_LIGHT_TRIANGLE(l), 1) << "world triangle id";
  EXPECT_EQ(LUX_LIGHT_MATERIAL(l), one_sided) << "material";
  EXPECT_FLOAT_EQ(l.emission.x, 2);  // emissive factor x strength
  EXPECT_FLOAT_EQ(l.emission.z, 6);
  EXPECT_FLOAT_EQ(LUX_LIGHT_AREA(l), 2);  // area
  EXPECT_FLOAT_EQ(l.axis.x, 2);           // edge1
  EXPECT_FLOAT_EQ(l.edge2.z, 2);          // edge2
  EXPECT_FLOAT_EQ(l.shape.y, -1) << "front normal follows the winding";
  EXPECT_EQ(LUX_LIGHT_FLAGS(l), 0);
  EXPECT_FLOAT_EQ(t->lights[1].shape.y, 1) << "a mirrored instance's front face is the other side";
  EXPECT_EQ(LUX_LIGHT_FLAGS(t->lights[2]), LUX_LIGHT_FLAG_DOUBLE_SIDED);
  // Double-sided emitters emit (and are chosen) twice as much per area.
  const double per_area_one = pmf(t.value(), 0) / 2.0 / luminance({2, 4, 6});
  const double per_area_two = pmf(t.value(), 2) / 0.5 / luminance({1, 1, 1});
  EXPECT_NEAR(per_area_two / per_area_one, 2.0, 1e-5);
  EXPECT_FALSE(t->has_point || t->has_sky);
}

TEST(LightTable, TexturedEmittersAreFlaggedAndWeighedByTheTextureMean) {
  SceneBuilder b;
  scene::Texture tex;
  tex.name = "glow";
  tex.width = 2;
  tex.height = 1;
  tex.rgba8 = {255, 255, 255, 255, 0, 0, 0, 255};  // mean luminance 0.5
  b.s.textures.push_back(tex);
  const int plain = b.add_emitter({1, 1, 1});
  const int textured = b.add_emitter({1, 1, 1});
  b.s.materials[static_cast<size_t>(textured)].emissive_texture.texture = 0;
  b.add_triangles({{0, 0, 0}, {1, 0, 0}, {0, 0, 1}}, plain);
  b.add_triangles({{0, 0, 0}, {1, 0, 0}, {0, 0, 1}}, textured);
  auto t = build(b);
  ASSERT_TRUE(t.is_ok()) << t.status().to_string();
  ASSERT_EQ(t->lights.size(), 2u);
  EXPECT_EQ(LUX_LIGHT_FLAGS(t->lights[1]), LUX_LIGHT_FLAG_TEXTURED);
  EXPECT_FLOAT_EQ(t->lights[1].emission.x, 1.0f)
      << "radiance is the constant; the caller applies the texture";
  EXPECT_NEAR(pmf(t.value(), 1) / pmf(t.value(), 0), 0.5, 1e-6);
}

TEST(LightTable, PowerlessLightsAreDroppedAndCounted) {
  SceneBuilder b;
  b.add_point({0, 1, 0}, {1, 1, 1}, 0.0f, "off");
  b.add_point({0, 1, 0}, {0, 0, 0}, 5.0f, "black");
  b.add_point({0, 1, 0}, {1, 1, 1}, 1.0f, "on");
  const int glow = b.add_emitter({1, 1, 1});
  b.add_triangles({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, glow);  // zero area
  LightSettings s;
  s.sky.kind = SkySettings::Kind::kConstant;
  s.sky.intensity = 0;
  auto t = build(b, s);
  ASSERT_TRUE(t.is_ok()) << t.status().to_string();
  EXPECT_EQ(t->lights.size(), 1u);
  EXPECT_EQ(t->dropped_zero_power, 4u);
  ASSERT_EQ(t->select.size(), 1u);
  EXPECT_EQ(t->select[0].pmf, 1.0f);
  EXPECT_EQ(t->select[0].threshold, 1.0f);
  EXPECT_FALSE(t->has_sky || t->has_emissive);
  EXPECT_EQ(t->sky.kind, LUX_SKY_KIND_NONE);
  EXPECT_EQ(t->sky.light, -1);
  EXPECT_EQ(t->triangle_light, (std::vector<int32_t>{-1}));

  auto empty = build(SceneBuilder());
  ASSERT_TRUE(empty.is_ok());
  EXPECT_TRUE(empty->lights.empty());
  EXPECT_TRUE(empty->select.empty());
}

TEST(LightTable, SunAndDirectionalDiscsStoreOneMinusCosAndDiscRadiance) {
  SceneBuilder b;
  b.add_directional({0, -1, 0}, {1, 1, 1}, 2.0f);
  LightSettings s;
  s.directional_angular_radius_degrees = 5;
  s.sun.enabled = true;
  s.sun.direction = {1, -1, 0};
  s.sun.illuminance = 1000;
  s.sun.angular_radius_degrees = 0.27f;
  auto t = build(b, s);
  ASSERT_TRUE(t.is_ok()) << t.status().to_string();
  ASSERT_EQ(t->lights.size(), 2u);
  const double a5 = 5 * kPi / 180;
  EXPECT_NEAR(LUX_LIGHT_ONE_MINUS_COS(t->lights[0]), 1 - std::cos(a5), 1e-9);
  EXPECT_NEAR(t->lights[0].emission.x, 2.0 / (kPi * std::sin(a5) * std::sin(a5)), 1e-3);
  const cl::LuxLight& sun = t->lights[1];
  const double a = 0.27 * kPi / 180;
  EXPECT_NEAR(LUX_LIGHT_ONE_MINUS_COS(sun) / (1 - std::cos(a)), 1.0, 1e-5)
      << "1 - cos kept to float precision";
  EXPECT_NEAR(sun.axis.x, std::sqrt(0.5), 1e-6) << "direction normalized";
  EXPECT_NEAR(pmf(t.value(), 1) / pmf(t.value(), 0), 500.0, 1e-3);
  device::FeatureSet f;
  add_light_features(t.value(), &f);
  EXPECT_EQ(f.build_options(), "-DLUX_LIGHT_DIRECTIONAL=1");
}

// Every error names what is at fault.
void expect_invalid(const Result<LightTable>& t, const std::string& needle) {
  ASSERT_FALSE(t.is_ok()) << "expected an error naming " << needle;
  EXPECT_EQ(t.status().code(), StatusCode::kInvalidArgument) << t.status().to_string();
  EXPECT_NE(t.status().message().find(needle), std::string::npos) << t.status().to_string();
}

TEST(LightTable, ErrorsNameTheLightMaterialOrSetting) {
  {
    SceneBuilder b;
    b.add_point({0, 1, 0}, {1, 1, 1}, -1.0f, "lamp");
    expect_invalid(build(b), "'lamp': intensity");
  }
  {
    SceneBuilder b;
    b.add_point({0, 1, 0}, {1, NAN, 1}, 1.0f, "nan lamp");
    expect_invalid(build(b), "'nan lamp': color");
  }
  {
    SceneBuilder b;
    b.add_spot({0, 1, 0}, {0, -1, 0}, {1, 1, 1}, 1.0f, 0.8f, 0.4f, "cone");
    expect_invalid(build(b), "'cone': spot cone angles");
  }
  {
    SceneBuilder b;
    const int m = b.add_emitter({1, 1, 1}, false, "lava");
    b.s.materials[static_cast<size_t>(m)].emissive_factor.y = -1;
    b.add_triangles({{0, 0, 0}, {1, 0, 0}, {0, 0, 1}}, m);
    expect_invalid(build(b), "'lava': emissive factor");
  }
  {
    SceneBuilder b;
    b.add_directional({0, -1, 0}, {1, 1, 1}, 1.0f, "sunlamp");
    LightSettings s;
    s.directional_angular_radius_degrees = 95;
    expect_invalid(build(b, s), "'sunlamp': angular radius");
  }
  LightSettings s;
  s.sun.enabled = true;
  s.sun.illuminance = -5;
  expect_invalid(build(SceneBuilder(), s), "sun: illuminance");
  s.sun.illuminance = 5;
  // Every direction that does not survive normalisation on every thread
  // (common/direction.h), named as the setting (settings.sun.direction).
  for (Vec3 d : {Vec3{0, 0, 0}, Vec3{1e-45f, 0, 0}, Vec3{1e-20f, 0, 0}, Vec3{3e38f, 3e38f, 0}}) {
    s.sun.direction = d;
    expect_invalid(build(SceneBuilder(), s), "settings.sun.direction: ");
  }
  s = {};
  s.sky.kind = SkySettings::Kind::kConstant;
  s.sky.intensity = -1;
  expect_invalid(build(SceneBuilder(), s), "sky: intensity");
  s.sky.intensity = 1;
  s.sky.kind = SkySettings::Kind::kEquirect;
  expect_invalid(build(SceneBuilder(), s), "equirect_path");
  s.sky.equirect_path = "/nonexistent/luxel/sky.hdr";
  expect_invalid(build(SceneBuilder(), s), "/nonexistent/luxel/sky.hdr");
}

TEST(LightTable, LightFeaturesFollowTheTypesPresent) {
  SceneBuilder b;
  b.add_point({0, 1, 0}, {1, 1, 1}, 1.0f);
  const int glow = b.add_emitter({1, 1, 1});
  b.add_triangles({{0, 0, 0}, {1, 0, 0}, {0, 0, 1}}, glow);
  LightSettings s;
  s.sky.kind = SkySettings::Kind::kConstant;
  auto t = build(b, s);
  ASSERT_TRUE(t.is_ok()) << t.status().to_string();
  device::FeatureSet f;
  add_light_features(t.value(), &f);
  EXPECT_EQ(f.build_options(), "-DLUX_LIGHT_EMISSIVE=1 -DLUX_LIGHT_POINT=1 -DLUX_SKY=1");
}

}  // namespace
}  // namespace luxel::pipeline
