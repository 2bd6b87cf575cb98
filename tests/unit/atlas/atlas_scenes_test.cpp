// The atlas and sample-info buffer on real scenes: the bundled scenes/ and
// the shared benchmark scenes beside the checkout (skipped when absent).
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "atlas/chart_geometry.h"
#include "atlas_test_util.h"
#include "kernels/shared/sample_info.h"
#include "scene/gltf_import.h"

namespace luxel::atlas::testing {
namespace {

namespace fs = std::filesystem;

scene::ImportOptions geometry_only() {
  scene::ImportOptions o;
  o.decode_textures = false;
  return o;
}

#define LOAD_SCENE(var, dir, file)                                                   \
  const fs::path var##_path = fs::path(dir) / (file);                                \
  if (!fs::exists(var##_path)) GTEST_SKIP() << var##_path << " not present";         \
  auto var##_result = scene::import_gltf_file(var##_path.string(), geometry_only()); \
  ASSERT_TRUE(var##_result.is_ok()) << var##_result.status().to_string();            \
  const scene::Scene& var = var##_result.value()

AtlasSettings at_resolution(int side) {
  AtlasSettings s;
  s.resolution = side;
  return s;
}

// Texels (area) of each instance's UV triangles in the atlas, from the mesh
// data and the placement alone.
std::vector<double> chart_texels(const scene::Scene& scene, const Atlas& atlas) {
  std::vector<double> out;
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    const auto& mesh = scene.meshes[static_cast<size_t>(scene.instances[i].mesh)];
    const auto& p = atlas.placements[i];
    out.push_back(measure_mesh_uvs(mesh).value().area * p.scale[0] * atlas.width * p.scale[1] *
                  atlas.height);
  }
  return out;
}

// Valid samples per instance / 64 (each sample counted once, for its first
// record): a Monte Carlo estimate of the instance's texel area.
std::vector<double> sampled_texels(const SampleInfo& info, size_t instances) {
  std::vector<double> out(instances, 0);
  for (uint32_t texel : info.covered_texels) {
    const uint32_t count = cl::lux_sample_info_count(info.words.data(), info.offsets[texel]);
    for (uint32_t rank = 0; rank < count; ++rank)
      out[sample_point(info, texel, rank).instance] += 1.0 / 64;
  }
  return out;
}

TEST(AtlasScenes, CornellBoxUsesItsOwnAtlas) {
  LOAD_SCENE(s, LUXEL_SCENES_DIR, "cornell_box.gltf");
  const Atlas atlas = expect_atlas(s, at_resolution(256));
  EXPECT_EQ(atlas.mode, AtlasMode::kShared);
  const SampleInfo info = expect_sample_info(s, atlas);
  const double expected = chart_texels(s, atlas)[0];
  const double sampled = sampled_texels(info, 1)[0];
  std::printf(
      "cornell_box.gltf at 256^2: %zu covered texels, UV area %.0f texels, sampled %.0f, "
      "%llu records, %llu contested samples, %.2f MB\n",
      info.covered_texels.size(), expected, sampled, static_cast<unsigned long long>(info.records),
      static_cast<unsigned long long>(info.contested_samples), info.bytes() / 1e6);
  EXPECT_NEAR(sampled, expected, 0.01 * expected);
  EXPECT_GE(static_cast<double>(info.covered_texels.size()), 0.99 * expected);
  EXPECT_LT(info.contested_samples, info.valid_samples / 1000);
  EXPECT_EQ(info.zero_uv_area_triangles, 0u);
}

TEST(AtlasScenes, FoliageInstancesArePacked) {
  LOAD_SCENE(s, LUXEL_SCENES_DIR, "foliage_instanced.glb");
  const Atlas atlas = expect_atlas(s, at_resolution(512));
  EXPECT_EQ(atlas.mode, AtlasMode::kPacked);
  expect_disjoint_padded(atlas, 2);
  const SampleInfo info = expect_sample_info(s, atlas);
  const std::vector<double> expected = chart_texels(s, atlas);
  const std::vector<double> sampled = sampled_texels(info, s.instances.size());
  double total_expected = 0, total_sampled = 0;
  for (size_t i = 0; i < expected.size(); ++i) {
    total_expected += expected[i];
    total_sampled += sampled[i];
    EXPECT_NEAR(sampled[i], expected[i], 0.1 * expected[i] + 2) << s.instances[i].name;
  }
  std::printf(
      "foliage_instanced.glb at 512^2: %.1f texels per m, chart area %.0f texels, "
      "sampled %.0f, %zu covered texels, %.2f MB\n",
      atlas.texels_per_unit, total_expected, total_sampled, info.covered_texels.size(),
      info.bytes() / 1e6);
  EXPECT_NEAR(total_sampled, total_expected, 0.02 * total_expected);
  // Packed rectangles are disjoint, so no texel holds two instances.
  for (size_t k = 0; k < info.covered_texels.size(); ++k) {
    const uint32_t o = info.offsets[info.covered_texels[k]];
    for (size_t r = 0; r < record_count(info, k); ++r)
      ASSERT_EQ(info.words[o + 2 + 4 * r + 2], info.words[o + 4])
          << "texel " << info.covered_texels[k];
  }
}

TEST(AtlasScenes, SharedCornellBoxIsASceneWideAtlas) {
  LOAD_SCENE(s, LUXEL_SHARED_SCENES_DIR, "cornell_box.glb");
  const Atlas atlas = expect_atlas(s, at_resolution(512));
  EXPECT_EQ(atlas.mode, AtlasMode::kShared);
  const SampleInfo info = expect_sample_info(s, atlas);
  double expected = 0;
  for (double t : chart_texels(s, atlas)) expected += t;
  const double sampled = static_cast<double>(info.valid_samples) / 64;
  EXPECT_NEAR(sampled, expected, 0.01 * expected);
  // README: 0.68 of the atlas is covered by triangles.
  EXPECT_NEAR(expected / (512.0 * 512.0), 0.68, 0.01);
}

// Build time and size on the shared benchmark scenes (run with
// --gtest_also_run_disabled_tests; figures for docs/performance.md).
TEST(AtlasScenes, DISABLED_SharedScenesTiming) {
  for (const char* file :
       {"cornell_box.glb", "breakfast_room.glb", "gas_station.glb", "sponza.glb"}) {
    const fs::path path = fs::path(LUXEL_SHARED_SCENES_DIR) / file;
    if (!fs::exists(path)) continue;
    auto s = scene::import_gltf_file(path.string(), geometry_only());
    ASSERT_TRUE(s.is_ok()) << s.status().to_string();
    for (int side : {1024, 2048, 4096}) {
      using clock = std::chrono::steady_clock;
      const auto t0 = clock::now();
      const Atlas atlas = expect_atlas(*s, at_resolution(side));
      const auto t1 = clock::now();
      const SampleInfo info = expect_sample_info(*s, atlas);
      const auto t2 = clock::now();
      const double covered = static_cast<double>(info.covered_texels.size());
      std::printf(
          "%-20s %5d^2 %-6s atlas %7.1f ms, sample info %8.1f ms, %8.2f MB "
          "(offsets %.2f), covered %.3f, %.3f records/texel, %llu contested, %zu zero-area\n",
          file, side, atlas_mode_name(atlas.mode),
          std::chrono::duration<double, std::milli>(t1 - t0).count(),
          std::chrono::duration<double, std::milli>(t2 - t1).count(), info.bytes() / 1e6,
          info.offsets.size() * 4 / 1e6, covered / (double(side) * side),
          static_cast<double>(info.records) / covered,
          static_cast<unsigned long long>(info.contested_samples), info.zero_uv_area_triangles);
      std::fflush(stdout);
    }
  }
}

}  // namespace
}  // namespace luxel::atlas::testing
