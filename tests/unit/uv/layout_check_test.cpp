// The independent layout check (tests/support/uv_layout_check.h) that the uv
// tests, the bench and the fuzz target rely on: it must see overlaps, count
// a centre on a shared edge once, and measure stretch and density.
#include <gtest/gtest.h>

#include "support/uv_layout_check.h"
#include "uv_meshes.h"

namespace luxel::uv::testing {
namespace {

// A scene of one mesh, one instance at identity, an 8x8 atlas in shared mode.
struct Fixture {
  scene::Scene scene;
  atlas::Atlas atlas;
  Fixture() {
    scene.meshes.emplace_back();
    scene.instances.emplace_back();
    scene.instances[0].mesh = 0;
    atlas.width = atlas.height = 8;
    atlas.placements.resize(1);
  }
  // A triangle with 3D corners p and UV corners uv (in texels of the atlas).
  void triangle(Vec3 a, Vec3 b, Vec3 c, Vec2 ua, Vec2 ub, Vec2 uc) {
    scene::Mesh& m = scene.meshes[0];
    for (auto [p, u] : {std::pair{a, ua}, std::pair{b, ub}, std::pair{c, uc}}) {
      const uint32_t v = add_vertex(m, p, {0, 0, 1});
      m.uv1[v] = {u.x / 8, u.y / 8};
      m.indices.push_back(v);
    }
  }
};

TEST(UvLayoutCheck, QuadSplitOnItsDiagonalCoversEachCentreOnce) {
  Fixture f;
  // A 4x4-texel square whose diagonal passes through texel centres.
  f.triangle({0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 0}, {4, 0}, {4, 4});
  f.triangle({0, 0, 0}, {4, 4, 0}, {0, 4, 0}, {0, 0}, {4, 4}, {0, 4});
  const luxel::testing::LayoutCheck c = luxel::testing::check_layout(f.scene, f.atlas);
  EXPECT_EQ(c.covered_texels, 16);
  EXPECT_EQ(c.overlapping_texels, 0);
  EXPECT_EQ(c.outside_triangles, 0);
  EXPECT_NEAR(c.stretch_l2, 1.0, 1e-12);
  EXPECT_NEAR(c.stretch_linf, 1.0, 1e-12);
  EXPECT_NEAR(c.density_min, 1.0, 1e-12);  // one texel per unit
}

TEST(UvLayoutCheck, SeesOverlapsOutsideAndStretch) {
  Fixture f;
  f.triangle({0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 0}, {4, 0}, {4, 4});
  // Clockwise in UV, overlapping the first on the centres (2.5, 0.5),
  // (3.5, 0.5), (3.5, 1.5) and (3.5, 2.5).
  f.triangle({0, 0, 0}, {4, 4, 0}, {4, 0, 0}, {2, 0}, {4, 4}, {4, 0});
  const luxel::testing::LayoutCheck a = luxel::testing::check_layout(f.scene, f.atlas);
  EXPECT_EQ(a.overlapping_texels, 4);
  EXPECT_GT(a.stretch_linf, 1.5);  // the second maps 2 UV texels to 4 units
  f.triangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {7.5f, 7.5f}, {8.5f, 7.5f}, {7.5f, 8.5f});
  f.triangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1}, {2, 2}, {3, 3});  // zero UV area
  const luxel::testing::LayoutCheck b = luxel::testing::check_layout(f.scene, f.atlas);
  EXPECT_EQ(b.outside_triangles, 1);
  EXPECT_EQ(b.zero_uv_triangles, 1);
  EXPECT_EQ(b.collapsed_triangles, 1);
}

}  // namespace
}  // namespace luxel::uv::testing
