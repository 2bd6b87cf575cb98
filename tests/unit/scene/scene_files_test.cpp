// Real scenes: the project's bundled scenes/ (every .gltf/.glb must import)
// and the shared benchmark scenes beside the checkout (skipped when absent).
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "common/clock.h"
#include "scene/gltf_import.h"
#include "scene/scene_stats.h"

namespace luxel::scene {
namespace {

namespace fs = std::filesystem;

TEST(SceneFiles, BundledScenesImport) {
  const fs::path dir = LUXEL_SCENES_DIR;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) GTEST_SKIP() << dir << " does not exist yet";
  int count = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir, ec)) {
    const auto ext = e.path().extension();
    if (!e.is_regular_file() || (ext != ".gltf" && ext != ".glb")) continue;
    auto r = import_gltf_file(e.path().string());
    ASSERT_TRUE(r.is_ok()) << e.path() << ": " << r.status().to_string();
    const SceneStats s = compute_stats(*r, 128);
    EXPECT_EQ(s.world_triangles > 0, !r->meshes.empty()) << e.path();
    ++count;
  }
  if (count == 0) GTEST_SKIP() << "no .gltf/.glb in " << dir << " yet";
}

// Loads a shared scene or skips the test when the folder is absent.
#define LOAD_SHARED(var, file, options)                                      \
  const fs::path var##_path = fs::path(LUXEL_SHARED_SCENES_DIR) / file;      \
  if (!fs::exists(var##_path)) GTEST_SKIP() << var##_path << " not present"; \
  auto var = import_gltf_file(var##_path.string(), options);                 \
  ASSERT_TRUE(var.is_ok()) << var.status().to_string()

// The README's triangle counts are of the files; import drops degenerate and
// zero-area triangles, which these tests print and bound.
void expect_triangles(const Scene& scene, size_t readme_count, const char* name) {
  const SceneStats s = compute_stats(scene, 16);
  std::printf("%s: %zu triangles imported, %zu degenerate dropped (README: %zu)\n", name,
              s.world_triangles, s.degenerate_triangles_dropped, readme_count);
  EXPECT_EQ(s.world_triangles + s.degenerate_triangles_dropped, readme_count);
  EXPECT_LE(s.degenerate_triangles_dropped, readme_count / 1000);
}

TEST(SharedScenes, CornellBox) {
  LOAD_SHARED(r, "cornell_box.glb", ImportOptions{});
  const SceneStats s = compute_stats(*r, 1024);
  EXPECT_EQ(s.world_triangles, 32u);
  EXPECT_EQ(s.degenerate_triangles_dropped, 0u);
  bool found = false;
  for (const auto& m : r->materials) {
    if (m.is_emissive()) {
      EXPECT_FLOAT_EQ(m.emissive_strength, 17.0f);
      EXPECT_NEAR(m.emissive_factor.y, 0.706f, 1e-3f);
      found = true;
    }
  }
  EXPECT_TRUE(found);
  EXPECT_EQ(s.emissive_triangles, 2u);
  EXPECT_GT(s.emissive_power, 0.0);
  // README: 0.68 of the atlas area covered, no overlap.
  EXPECT_NEAR(s.lightmap_coverage, 0.68, 0.02);
  EXPECT_EQ(s.lightmap_overlap_texels, 0u);
  EXPECT_EQ(s.lightmap_shared_texels, 0u) << "one atlas for all 16 meshes";
  std::printf("%s", format_stats(s).c_str());
}

TEST(SharedScenes, Sponza) {
  const auto t0 = std::chrono::steady_clock::now();
  LOAD_SHARED(r, "sponza.glb", ImportOptions{});
  const double secs = seconds_since(t0);
  std::printf("sponza: imported in %.2f s, %zu textures, %.1f MiB of import budget at the peak\n",
              secs, r->textures.size(), r->import_stats.peak_reserved_bytes / 1048576.0);
  expect_triangles(*r, 262087, "sponza");
  // 49 images: 24 base colour (sRGB), 14 metallic-roughness and 11 normal
  // maps (linear); no image is used both as sRGB and as linear data.
  EXPECT_EQ(r->textures.size(), 49u);
  size_t normal_mapped = 0;
  for (const auto& m : r->materials) normal_mapped += m.normal_texture.texture >= 0;
  EXPECT_GT(normal_mapped, 0u);
  // Meshes of normal-mapped materials carry unit tangents on every vertex.
  size_t with_tangents = 0;
  for (const Mesh& mesh : r->meshes) {
    bool mapped = false;
    for (int32_t m : mesh.triangle_material)
      mapped = mapped || r->materials[static_cast<size_t>(m)].normal_texture.texture >= 0;
    if (!mapped) {
      EXPECT_TRUE(mesh.tangents.empty()) << mesh.name;
      continue;
    }
    ++with_tangents;
    ASSERT_EQ(mesh.tangents.size(), mesh.positions.size()) << mesh.name;
    for (size_t i = 0; i < mesh.indices.size(); ++i) {
      const Vec4 t = mesh.tangents[mesh.indices[i]];
      if (r->materials[static_cast<size_t>(mesh.triangle_material[i / 3])].normal_texture.texture <
          0)
        continue;
      ASSERT_NEAR(length(Vec3{t.x, t.y, t.z}), 1.0f, 1e-3f) << mesh.name;
      ASSERT_TRUE(t.w == 1.0f || t.w == -1.0f) << mesh.name;
    }
  }
  EXPECT_GT(with_tangents, 0u);
  EXPECT_GT(compute_stats(*r, 16).alpha_masked_triangles, 0u);
  bool masked = false;
  for (const auto& m : r->materials)
    masked = masked || (m.alpha_mode == AlphaMode::kMask && m.double_sided);
  EXPECT_TRUE(masked);
}

TEST(SharedScenes, BreakfastRoomAndGasStation) {
  ImportOptions count_only;
  count_only.decode_textures = false;  // geometry is what is checked here
  {
    LOAD_SHARED(r, "breakfast_room.glb", count_only);
    expect_triangles(*r, 262687, "breakfast_room");
  }
  {
    LOAD_SHARED(g, "gas_station.glb", count_only);
    expect_triangles(*g, 99002, "gas_station");
    EXPECT_EQ(g->meshes.size(), 1102u);
  }
}

}  // namespace
}  // namespace luxel::scene
