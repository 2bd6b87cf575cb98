// Atlas layout: mode choice, packed rectangles, texel density, limits and
// error messages, on scenes built in code.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "atlas/chart_geometry.h"
#include "atlas/shelf_packer.h"
#include "atlas_test_util.h"

namespace luxel::atlas::testing {
namespace {

AtlasSettings at_resolution(int side, int padding = 2) {
  AtlasSettings s;
  s.resolution = side;
  s.padding_texels = padding;
  return s;
}

AtlasSettings at_density(float density, int max_resolution = 8192) {
  AtlasSettings s;
  s.texel_density = density;
  s.max_resolution = max_resolution;
  return s;
}

// Five instances of one unit quad mesh at different (some non-uniform) scales.
SceneBuilder instanced_quads() {
  SceneBuilder b;
  const int quad = add_quad(b, 0, 0, 1, 1);
  const double scales[5][2] = {{1, 1}, {2, 2}, {3, 1}, {0.5, 4}, {1.5, 1.5}};
  for (int i = 0; i < 5; ++i)
    b.instance(quad, scale_translate(scales[i][0], scales[i][1], 1, 10.0 * i));
  return b;
}

// Every instance's achieved density (texels per world unit) equals the atlas's.
void expect_uniform_density(const scene::Scene& scene, const Atlas& atlas) {
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    const auto& inst = scene.instances[i];
    const auto& mesh = scene.meshes[static_cast<size_t>(inst.mesh)];
    const double world = instance_world_area(mesh, inst);
    const double uv = measure_mesh_uvs(mesh).value().area;
    const auto& p = atlas.placements[i];
    EXPECT_NEAR(p.scale[0], p.scale[1], 1e-7);
    const double texels = uv * p.scale[0] * atlas.width * p.scale[1] * atlas.height;
    EXPECT_NEAR(std::sqrt(texels / world), atlas.texels_per_unit, 1e-5 * atlas.texels_per_unit)
        << "instance " << i;
  }
}

// The chart of each instance, mapped with its placement, lies in its rectangle.
void expect_charts_in_rects(const scene::Scene& scene, const Atlas& atlas) {
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    const auto& mesh = scene.meshes[static_cast<size_t>(scene.instances[i].mesh)];
    const int* r = atlas.placements[i].rect;
    for (const Vec2& uv : mesh.uv1) {
      const Vec2 a = atlas.to_atlas(static_cast<uint32_t>(i), uv);
      EXPECT_GT(a.x * atlas.width, r[0]);
      EXPECT_LT(a.x * atlas.width, r[0] + r[2]);
      EXPECT_GT(a.y * atlas.height, r[1]);
      EXPECT_LT(a.y * atlas.height, r[1] + r[3]);
    }
  }
}

TEST(AtlasLayout, SingleInstanceUsesTexcoord1AsIs) {
  SceneBuilder b;
  b.instance(add_quad(b, 0.1f, 0.2f, 0.6f, 0.9f));
  const Atlas atlas = expect_atlas(b.scene, at_resolution(64));
  EXPECT_EQ(atlas.mode, AtlasMode::kShared);
  EXPECT_EQ(atlas.width, 64);
  EXPECT_EQ(atlas.height, 64);
  ASSERT_EQ(atlas.placements.size(), 1u);
  const Vec2 uv{0.3f, 0.7f};
  EXPECT_EQ(atlas.to_atlas(0, uv).x, uv.x);
  EXPECT_EQ(atlas.to_atlas(0, uv).y, uv.y);
  EXPECT_EQ(atlas.placements[0].rect[2], 64);
}

TEST(AtlasLayout, DisjointMeshesShareTheAtlas) {
  SceneBuilder b;
  b.instance(add_quad(b, 0.0f, 0.0f, 0.45f, 1.0f));
  b.instance(add_quad(b, 0.55f, 0.0f, 1.0f, 1.0f), scale_translate(1, 1, 1, 5, 0, 0));
  EXPECT_EQ(expect_atlas(b.scene, at_resolution(128)).mode, AtlasMode::kShared);
}

TEST(AtlasLayout, OverlappingPerMeshLayoutsArePacked) {
  SceneBuilder b;
  b.instance(add_quad(b, 0, 0, 1, 1));
  b.instance(add_quad(b, 0, 0, 1, 1), scale_translate(2, 1, 1, 3, 0, 0));
  const Atlas atlas = expect_atlas(b.scene, at_resolution(128));
  EXPECT_EQ(atlas.mode, AtlasMode::kPacked);
  expect_disjoint_padded(atlas, 2);
  expect_uniform_density(b.scene, atlas);
}

TEST(AtlasLayout, InstancedMeshIsPackedWithUniformDensity) {
  SceneBuilder b = instanced_quads();
  for (int padding : {0, 2, 5}) {
    const Atlas atlas = expect_atlas(b.scene, at_resolution(256, padding));
    EXPECT_EQ(atlas.mode, AtlasMode::kPacked);
    ASSERT_EQ(atlas.placements.size(), 5u);
    expect_disjoint_padded(atlas, padding);
    expect_uniform_density(b.scene, atlas);
    expect_charts_in_rects(b.scene, atlas);
    // The largest density that fits: a few percent more does not fit.
    std::vector<ChartExtent> charts;
    for (const auto& inst : b.scene.instances)
      charts.push_back({1, 1, std::sqrt(instance_world_area(b.scene.meshes[0], inst))});
    std::vector<std::array<int, 2>> sizes;
    for (const auto& c : charts) {
      const int side = static_cast<int>(std::floor(c.stretch * atlas.texels_per_unit * 1.03 +
                                                   2 * kChartInsetTexels)) +
                       1;
      sizes.push_back({side, side});
    }
    EXPECT_TRUE(shelf_pack(sizes, 256, padding).empty()) << "padding " << padding;
  }
}

TEST(AtlasLayout, PackedChartsLeaveTheirRectanglesEmptyOutside) {
  // Rasterised coverage of each instance stays inside its own rectangle.
  SceneBuilder b = instanced_quads();
  const Atlas atlas = expect_atlas(b.scene, at_resolution(128));
  const SampleInfo info = expect_sample_info(b.scene, atlas);
  for (uint32_t texel : info.covered_texels) {
    const int x = static_cast<int>(texel) % info.width, y = static_cast<int>(texel) / info.width;
    const uint32_t offset = info.offsets[texel];
    const uint32_t instance = info.words[offset + 4];
    const int* r = atlas.placements[instance].rect;
    EXPECT_TRUE(x >= r[0] && x < r[0] + r[2] && y >= r[1] && y < r[1] + r[3]) << x << "," << y;
  }
}

TEST(AtlasLayout, SharedTexelDensityGivesTheResolution) {
  // 10 x 10 world quad on a UV chart of area 0.25.
  SceneBuilder b;
  b.instance(add_quad(b, 0.25f, 0.25f, 0.75f, 0.75f), scale_translate(20, 20, 1));
  const float density = 3.2f;
  const Atlas atlas = expect_atlas(b.scene, at_density(density));
  const double expected = std::ceil(std::sqrt(100.0 * density * density / 0.25));
  EXPECT_EQ(atlas.mode, AtlasMode::kShared);
  EXPECT_EQ(atlas.width, static_cast<int>(expected));
  EXPECT_NEAR(atlas.texels_per_unit, density, 0.05 * density);
  EXPECT_GE(atlas.texels_per_unit, density * (1 - 1e-6));
}

TEST(AtlasLayout, PackedTexelDensityGivesTheSmallestFittingSide) {
  SceneBuilder b = instanced_quads();
  const float density = 7.5f;
  const Atlas atlas = expect_atlas(b.scene, at_density(density));
  EXPECT_EQ(atlas.mode, AtlasMode::kPacked);
  EXPECT_EQ(atlas.width % 4, 0);
  EXPECT_NEAR(atlas.texels_per_unit, density, 1e-6);
  expect_disjoint_padded(atlas, 2);
  expect_uniform_density(b.scene, atlas);
  // Four texels less cannot hold the charts at that density.
  const Atlas smaller = expect_atlas(b.scene, at_resolution(atlas.width - 4));
  EXPECT_LT(smaller.texels_per_unit, density);
}

TEST(AtlasLayout, ZeroWorldAreaInstanceGetsOneTexel) {
  SceneBuilder b = instanced_quads();
  b.instance(0, scale_translate(0, 0, 0));
  const Atlas atlas = expect_atlas(b.scene, at_resolution(128));
  const int* r = atlas.placements.back().rect;
  EXPECT_EQ(r[2], 1);
  EXPECT_EQ(r[3], 1);
  expect_disjoint_padded(atlas, 2);
}

// --- limits and errors ------------------------------------------------------

void expect_error(const Result<Atlas>& r, StatusCode code, const std::string& needle) {
  ASSERT_FALSE(r.is_ok());
  EXPECT_EQ(r.status().code(), code) << r.status().to_string();
  EXPECT_NE(r.status().message().find(needle), std::string::npos)
      << "'" << needle << "' not in: " << r.status().message();
}

TEST(AtlasErrors, SettingsAreNamed) {
  SceneBuilder b;
  b.instance(add_quad(b, 0, 0, 1, 1));
  expect_error(build_atlas(b.scene, at_resolution(-3)), StatusCode::kInvalidArgument, "resolution");
  expect_error(build_atlas(b.scene, AtlasSettings{}), StatusCode::kInvalidArgument,
               "texel_density");
  expect_error(build_atlas(b.scene, at_density(NAN)), StatusCode::kInvalidArgument,
               "texel_density");
  expect_error(build_atlas(b.scene, at_resolution(64, -1)), StatusCode::kInvalidArgument,
               "padding_texels");
  AtlasSettings big = at_resolution(10000);
  expect_error(build_atlas(b.scene, big), StatusCode::kResourceExhausted, "largest lightmap side");
}

TEST(AtlasErrors, SceneWithoutInstances) {
  SceneBuilder b;
  add_quad(b, 0, 0, 1, 1);
  expect_error(build_atlas(b.scene, at_resolution(64)), StatusCode::kInvalidArgument,
               "scene has no geometry");
}

TEST(AtlasErrors, MissingAndDegenerateLightmapUvsNameTheMesh) {
  SceneBuilder b;
  b.instance(add_quad(b, 0, 0, 1, 1));
  b.scene.meshes[0].name = "Statue";
  b.scene.meshes[0].uv1.clear();
  expect_error(build_atlas(b.scene, at_resolution(64)), StatusCode::kInvalidArgument,
               "mesh 'Statue' has no TEXCOORD_1");

  SceneBuilder d;
  d.instance(d.add_mesh({{0.5f, 0.5f}, {0.5f, 0.5f}, {0.2f, 0.2f}, {0.8f, 0.8f}},
                        {0, 1, 2, 0, 2, 3}, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}));
  d.scene.meshes[0].name = "Folded";
  expect_error(build_atlas(d.scene, at_resolution(64)), StatusCode::kInvalidArgument, "'Folded'");
}

TEST(AtlasErrors, UvsOutsideTheUnitSquareInSharedMode) {
  SceneBuilder b;
  b.instance(add_quad(b, 0.5f, 0.5f, 1.25f, 1.0f));
  b.scene.meshes[0].name = "Overhang";
  expect_error(build_atlas(b.scene, at_resolution(64)), StatusCode::kInvalidArgument,
               "mesh 'Overhang'");
  // The same layout on an instanced mesh is packed by its bounding box.
  b.instance(0, scale_translate(1, 1, 1, 4));
  EXPECT_EQ(expect_atlas(b.scene, at_resolution(64)).mode, AtlasMode::kPacked);
}

// A density past the page is lowered to fit it, as Unity scales charts down
// past its largest lightmap, with a warning naming both densities and the
// option to raise.
TEST(AtlasLayout, DensityAboveThePageIsLoweredWithAWarning) {
  SceneBuilder b;
  b.instance(add_quad(b, 0, 0, 1, 1), scale_translate(100, 100, 1));
  // 100 x 100 world units at 200 texels per unit would need a 20000^2 atlas.
  const Atlas shared = expect_atlas(b.scene, at_density(200));
  EXPECT_EQ(shared.width, 8192);
  EXPECT_NEAR(shared.texels_per_unit, 81.92, 1e-3);
  ASSERT_EQ(shared.warnings.size(), 1u);
  EXPECT_NE(shared.warnings[0].find("lowered from 200 to 81.9"), std::string::npos)
      << shared.warnings[0];
  EXPECT_NE(shared.warnings[0].find("--max-resolution"), std::string::npos);
  SceneBuilder p = instanced_quads();
  const Atlas packed = expect_atlas(p.scene, at_density(5000, 4096));
  EXPECT_EQ(packed.mode, AtlasMode::kPacked);
  EXPECT_EQ(packed.width, 4096);
  EXPECT_LT(packed.texels_per_unit, 5000);
  expect_uniform_density(p.scene, packed);
  ASSERT_EQ(packed.warnings.size(), 1u);
  EXPECT_NE(packed.warnings[0].find("lowered from 5000"), std::string::npos);
  // Within the page: the density asked, no warning.
  EXPECT_TRUE(expect_atlas(p.scene, at_density(5, 4096)).warnings.empty());
}

// The default size: kDefaultTexelDensity texels per unit, so a 1 m and a
// 10 m square differ by 10 in side, held to the default page past it.
TEST(AtlasLayout, DefaultDensityScalesTheSideWithTheScene) {
  auto side_of = [](double metres) {
    SceneBuilder b;
    // A unit quad filling the UV square: side = ceil(metres * d).
    b.instance(add_quad(b, 0, 0, 1, 1), scale_translate(metres, metres, 1));
    return expect_atlas(b.scene, at_density(kDefaultTexelDensity, kDefaultMaxResolution));
  };
  const Atlas one = side_of(1), ten = side_of(10), hundred = side_of(100);
  EXPECT_NEAR(one.width, 40, 1);
  EXPECT_NEAR(ten.width, 400, 1);
  EXPECT_NEAR(one.texels_per_unit, 40, 1e-3);
  EXPECT_NEAR(ten.texels_per_unit, 40, 1e-3);
  EXPECT_TRUE(one.warnings.empty() && ten.warnings.empty());
  EXPECT_EQ(hundred.width, kDefaultMaxResolution);
  EXPECT_NEAR(hundred.texels_per_unit, 1024 / 100.0, 1e-3);
  EXPECT_EQ(hundred.warnings.size(), 1u);
}

TEST(AtlasErrors, TooManyChartsForTheResolution) {
  SceneBuilder b;
  const int quad = add_quad(b, 0, 0, 1, 1);
  for (int i = 0; i < 40; ++i) b.instance(quad, scale_translate(1, 1, 1, 2.0 * i));
  // 40 charts of at least 1 texel + 2 padding need more than 16^2 texels.
  expect_error(build_atlas(b.scene, at_resolution(16)), StatusCode::kResourceExhausted,
               "40 lightmap charts");
  expect_error(build_atlas(b.scene, at_resolution(16)), StatusCode::kResourceExhausted,
               "raise --resolution");
}

TEST(AtlasErrors, InstanceWithABadMeshIndex) {
  SceneBuilder b;
  b.instance(add_quad(b, 0, 0, 1, 1));
  b.instance(7);
  expect_error(build_atlas(b.scene, at_resolution(64)), StatusCode::kInvalidArgument, "node1");
}

}  // namespace
}  // namespace luxel::atlas::testing
