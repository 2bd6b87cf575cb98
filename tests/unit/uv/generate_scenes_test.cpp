// generate_lightmap_uvs (uv/generate.h) on the shared benchmark scenes
// (../shared/scenes, skipped when absent) with their TEXCOORD_1 stripped:
// generation succeeds, no texel centre of the laid-out atlas is inside two
// triangles (an independent rasteriser, tests/support/uv_layout_check.h), and
// stretch (Sander et al. 2001, §3) and packing efficiency stay within bounds
// set from measurements (docs/performance.md, "Lightmap UV generation").
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "scene/gltf_import.h"
#include "support/uv_layout_check.h"
#include "uv/generate.h"

namespace luxel::uv::testing {
namespace {

struct Bounds {
  const char* file;
  int resolution;
  // UvReport: area-weighted L2 and worst-triangle Linf after each chart's
  // area normalisation.
  double max_l2, max_linf;
  // The final atlas against world space, one normalisation for the scene.
  double max_atlas_l2, max_atlas_linf;
  double min_efficiency;  // UvReport::efficiency (covered mask texels / atlas)
};

void run(const Bounds& b) {
  const std::filesystem::path path = std::filesystem::path(LUXEL_SHARED_SCENES_DIR) / b.file;
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not present";
  scene::ImportOptions io;
  io.decode_textures = false;
  auto s = scene::import_gltf_file(path.string(), io);
  ASSERT_TRUE(s.is_ok()) << s.status().to_string();
  size_t triangles = 0;
  for (scene::Mesh& m : s->meshes) {
    m.uv1.assign(m.positions.size(), Vec2{0, 0});
    m.has_lightmap_uvs = false;
    triangles += m.triangle_count();
  }
  GenerateOptions o;
  o.atlas.resolution = b.resolution;
  auto g = generate_lightmap_uvs(*s, o);
  ASSERT_TRUE(g.is_ok()) << g.status().to_string();
  const UvReport& r = g->report;
  EXPECT_EQ(g->atlas.width, b.resolution);
  EXPECT_EQ(g->atlas.height, b.resolution);
  EXPECT_EQ(r.triangles, triangles);
  EXPECT_LE(r.unplaced_triangles, triangles / 1000);
  const luxel::testing::LayoutCheck check = luxel::testing::check_layout(g->scene, g->atlas);
  EXPECT_EQ(check.overlapping_texels, 0);
  EXPECT_EQ(check.outside_triangles, 0);
  EXPECT_LE(r.stretch_l2, b.max_l2);
  EXPECT_LE(r.stretch_linf, b.max_linf);
  EXPECT_LE(check.stretch_l2, b.max_atlas_l2);
  EXPECT_LE(check.stretch_linf, b.max_atlas_linf);
  EXPECT_GE(r.efficiency, b.min_efficiency);
  // One texel density for the whole scene (UV area against world area per
  // instance, measured independently of UvReport::density_spread).
  EXPECT_LE(check.density_max, 1.01 * check.density_min);
  // Triangles with 3D area but no UV area are the report's unplaced ones.
  EXPECT_LE(static_cast<size_t>(check.collapsed_triangles), r.unplaced_triangles);
  std::printf(
      "%s at %d: %zu charts, %zu unplaced, efficiency %.3f, stretch L2 %.4f Linf %.3f, atlas "
      "L2 %.4f Linf %.3f, covered %lld, %.2f s\n",
      b.file, b.resolution, r.charts, r.unplaced_triangles, r.efficiency, r.stretch_l2,
      r.stretch_linf, check.stretch_l2, check.stretch_linf, check.covered_texels, r.total_seconds);
}

// Bounds from the measurements (docs/performance.md, "Lightmap UV
// generation"; same resolution) with a margin: L2 <= 1.005, Linf about 25 %
// above the measured value, efficiency 3 points below it.
//   Cornell box 256^2:   L2 1.0000, Linf 1.000, atlas 1.0000 / 1.000, eff. 64.5 %
//   breakfast room 2048^2: L2 1.0003, Linf 1.467, atlas 1.0003 / 1.468, eff. 75.0 %
//   gas station 2048^2:  L2 1.0000, Linf 1.725, atlas 1.0000 / 1.725, eff. 69.4 %
//   Sponza 2048^2:       L2 1.0008, Linf 2.155, atlas 1.0008 / 2.152, eff. 70.7 %
TEST(UvGenerateScenes, CornellBox) {
  run({"cornell_box.glb", 256, 1.005, 1.01, 1.005, 1.01, 0.61});
}
TEST(UvGenerateScenes, BreakfastRoom) {
  run({"breakfast_room.glb", 2048, 1.005, 1.85, 1.005, 1.85, 0.72});
}
TEST(UvGenerateScenes, GasStation) {
  run({"gas_station.glb", 2048, 1.005, 2.15, 1.005, 2.15, 0.66});
}
TEST(UvGenerateScenes, Sponza) {
  run({"sponza.glb", 2048, 1.005, 2.7, 1.005, 2.7, 0.67});
}

}  // namespace
}  // namespace luxel::uv::testing
