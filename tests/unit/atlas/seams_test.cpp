// find_seams on hand-built meshes whose seams are known: a quad cut along
// its diagonal into two charts, the same quad with split vertices that keep
// their UVs (no seam), a fan of three triangles on one edge (non-manifold),
// and one mesh used by two packed instances.
#include "atlas/seams.h"

#include <gtest/gtest.h>

#include <cmath>

#include "atlas_test_util.h"

namespace luxel::atlas {
namespace {

using testing::SceneBuilder;

const std::vector<Vec3> kQuad = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 0, 0}, {1, 1, 0}, {0, 1, 0}};

bool near(Vec2 p, Vec2 q) {
  return std::abs(p.x - q.x) < 1e-4f && std::abs(p.y - q.y) < 1e-4f;
}

// Triangle 0 (P0 P1 P2) in the left half of the atlas, triangle 1 (P0 P2 P3)
// in the right half: the diagonal P0-P2 is a seam.
TEST(Seams, QuadCutIntoTwoChartsHasOneSeamWithMatchingEndpoints) {
  SceneBuilder b;
  b.add_mesh({{0.1f, 0.1f}, {0.4f, 0.1f}, {0.4f, 0.4f}, {0.6f, 0.1f}, {0.9f, 0.4f}, {0.6f, 0.4f}},
             {0, 1, 2, 3, 4, 5}, kQuad);
  b.instance(0);
  AtlasSettings s;
  s.resolution = 20;
  const Atlas atlas = testing::expect_atlas(b.scene, s);
  ASSERT_EQ(atlas.mode, AtlasMode::kShared);
  const SeamSet seams = find_seams(b.scene, atlas);
  ASSERT_EQ(seams.edges.size(), 1u);
  EXPECT_EQ(seams.non_manifold, 0u);
  const SeamEdge& e = seams.edges[0];
  // In texels (x 20): P0 -> (2, 2) and (12, 2); P2 -> (8, 8) and (18, 8).
  const Vec2 a_p0{2, 2}, b_p0{12, 2}, a_p2{8, 8}, b_p2{18, 8};
  auto pair_is = [&](Vec2 x, Vec2 y, Vec2 p, Vec2 q) {
    return (near(x, p) && near(y, q)) || (near(x, q) && near(y, p));
  };
  // a0/b0 image one vertex, a1/b1 the other.
  const bool p0_first = pair_is(e.a0, e.b0, a_p0, b_p0) && pair_is(e.a1, e.b1, a_p2, b_p2);
  const bool p2_first = pair_is(e.a0, e.b0, a_p2, b_p2) && pair_is(e.a1, e.b1, a_p0, b_p0);
  EXPECT_TRUE(p0_first || p2_first) << e.a0.x << "," << e.a0.y << " " << e.b0.x << "," << e.b0.y;
}

// Each seam carries the width of the narrower chart it joins: the shorter
// side of the chart's box in the atlas. Here both triangles are charts of
// 0.3 x 0.3 (6 x 6 texels); with the right one squeezed to 0.3 x 0.05 (a
// sliver one texel high) the seam's width is that texel.
TEST(Seams, SeamCarriesTheNarrowerChartsWidth) {
  for (const float top : {0.4f, 0.15f}) {
    SceneBuilder b;
    b.add_mesh({{0.1f, 0.1f}, {0.4f, 0.1f}, {0.4f, 0.4f}, {0.6f, 0.1f}, {0.9f, top}, {0.6f, top}},
               {0, 1, 2, 3, 4, 5}, kQuad);
    b.instance(0);
    AtlasSettings s;
    s.resolution = 20;
    const SeamSet seams = find_seams(b.scene, testing::expect_atlas(b.scene, s));
    ASSERT_EQ(seams.edges.size(), 1u);
    EXPECT_NEAR(seams.edges[0].chart_texels, 20 * (top - 0.1f), 1e-3f) << top;
  }
}

// Triangles joined by an edge whose uv1 images coincide are one chart. T0
// and T1 share B-C (the same vertices): each alone spans 3 texels in x, the
// two together 6. T2 meets T1 along C-D with vertices of its own (other
// UVs): the one seam, to a chart 6 texels wide. Widths taken per triangle
// would give 3.
TEST(Seams, ChartsFollowUvConnectivity) {
  SceneBuilder b;
  b.add_mesh(
      {{0.1f, 0.1f},
       {0.25f, 0.1f},
       {0.25f, 0.4f},
       {0.4f, 0.1f},  // A B C D
       {0.6f, 0.4f},
       {0.6f, 0.1f},
       {0.9f, 0.25f}},  // C' D' E
      {0, 1, 2, 1, 3, 2, 4, 5, 6},
      {{0, 0, 0}, {0.5f, 0, 0}, {0.5f, 1, 0}, {1, 0, 0}, {0.5f, 1, 0}, {1, 0, 0}, {1.5f, 0.5f, 0}});
  b.instance(0);
  AtlasSettings s;
  s.resolution = 20;
  const SeamSet seams = find_seams(b.scene, testing::expect_atlas(b.scene, s));
  ASSERT_EQ(seams.edges.size(), 1u);
  EXPECT_NEAR(seams.edges[0].chart_texels, 6.0f, 1e-3f);
}

// The same cut, but the second triangle's vertices carry another normal
// (a hard edge): the lighting may jump there, so it is no seam.
TEST(Seams, HardEdgeIsCountedNotStitched) {
  SceneBuilder b;
  b.add_mesh({{0.1f, 0.1f}, {0.4f, 0.1f}, {0.4f, 0.4f}, {0.6f, 0.1f}, {0.9f, 0.4f}, {0.6f, 0.4f}},
             {0, 1, 2, 3, 4, 5}, kQuad);
  for (int v = 3; v < 6; ++v) b.scene.meshes[0].normals[v] = {0, 0.1f, 1};  // 5.7 degrees off
  b.instance(0);
  AtlasSettings s;
  s.resolution = 20;
  const SeamSet seams = find_seams(b.scene, testing::expect_atlas(b.scene, s));
  EXPECT_TRUE(seams.edges.empty());
  EXPECT_EQ(seams.hard_edges, 1u);
}

TEST(Seams, SplitVerticesWithEqualUvsAreNoSeam) {
  SceneBuilder b;
  b.add_mesh({{0.1f, 0.1f}, {0.4f, 0.1f}, {0.4f, 0.4f}, {0.1f, 0.1f}, {0.4f, 0.4f}, {0.1f, 0.4f}},
             {0, 1, 2, 3, 4, 5}, kQuad);
  b.instance(0);
  AtlasSettings s;
  s.resolution = 20;
  EXPECT_TRUE(find_seams(b.scene, testing::expect_atlas(b.scene, s)).edges.empty());
}

TEST(Seams, EdgeOfThreeTrianglesIsSkippedAsNonManifold) {
  SceneBuilder b;
  // Three triangles on the edge (0,0,0)-(1,0,0), each in its own chart.
  b.add_mesh({{0.1f, 0.1f},
              {0.3f, 0.1f},
              {0.2f, 0.3f},
              {0.4f, 0.1f},
              {0.6f, 0.1f},
              {0.5f, 0.3f},
              {0.7f, 0.1f},
              {0.9f, 0.1f},
              {0.8f, 0.3f}},
             {0, 1, 2, 3, 4, 5, 6, 7, 8},
             {{0, 0, 0},
              {1, 0, 0},
              {0.5f, 1, 0},
              {0, 0, 0},
              {1, 0, 0},
              {0.5f, 0, 1},
              {0, 0, 0},
              {1, 0, 0},
              {0.5f, -1, 0}});
  b.instance(0);
  AtlasSettings s;
  s.resolution = 20;
  const SeamSet seams = find_seams(b.scene, testing::expect_atlas(b.scene, s));
  EXPECT_TRUE(seams.edges.empty());
  EXPECT_EQ(seams.non_manifold, 1u);
}

// Two instances of one mesh are packed into their own rectangles: each gets
// its own copy of the seam, inside its rectangle.
TEST(Seams, EveryInstanceGetsItsOwnSeamInItsRectangle) {
  SceneBuilder b;
  b.add_mesh({{0.1f, 0.1f}, {0.4f, 0.1f}, {0.4f, 0.4f}, {0.6f, 0.1f}, {0.9f, 0.4f}, {0.6f, 0.4f}},
             {0, 1, 2, 3, 4, 5}, kQuad);
  b.instance(0);
  b.instance(0, testing::scale_translate(1, 1, 1, 5, 0, 0));
  AtlasSettings s;
  s.resolution = 64;
  const Atlas atlas = testing::expect_atlas(b.scene, s);
  ASSERT_EQ(atlas.mode, AtlasMode::kPacked);
  const SeamSet seams = find_seams(b.scene, atlas);
  ASSERT_EQ(seams.edges.size(), 2u);
  for (const SeamEdge& e : seams.edges) {
    const InstancePlacement& p = atlas.placements[e.instance];
    for (Vec2 v : {e.a0, e.a1, e.b0, e.b1}) {
      EXPECT_GE(v.x, p.rect[0] - 1e-3f);
      EXPECT_LE(v.x, p.rect[0] + p.rect[2] + 1e-3f);
      EXPECT_GE(v.y, p.rect[1] - 1e-3f);
      EXPECT_LE(v.y, p.rect[1] + p.rect[3] + 1e-3f);
    }
  }
  EXPECT_NE(seams.edges[0].instance, seams.edges[1].instance);
}

// Pages stacked from the top (atlas.h): a seam inside page 1 comes out in
// page 1's own coordinates; one whose sides lie on two pages is skipped.
TEST(Seams, SeamsArePageLocalAndCrossPageSeamsAreSkipped) {
  Atlas atlas;
  atlas.width = 20;
  atlas.height = 40;
  atlas.pages = 2;
  atlas.mode = AtlasMode::kGenerated;
  atlas.placements.resize(1);
  for (bool across : {false, true}) {
    SceneBuilder b;
    // Side A on page 1 (v in [0.55, 0.7]); side B on page 1 too, or on page 0.
    const float vb = across ? 0.05f : 0.55f;
    b.add_mesh({{0.1f, 0.55f},
                {0.4f, 0.55f},
                {0.4f, 0.7f},
                {0.6f, vb},
                {0.9f, vb + 0.15f},
                {0.6f, vb + 0.15f}},
               {0, 1, 2, 3, 4, 5}, kQuad);
    b.instance(0);
    const SeamSet seams = find_seams(b.scene, atlas);
    if (across) {
      EXPECT_TRUE(seams.edges.empty());
      EXPECT_EQ(seams.cross_page, 1u);
      continue;
    }
    ASSERT_EQ(seams.edges.size(), 1u);
    const SeamEdge& e = seams.edges[0];
    EXPECT_EQ(e.page, 1);
    // v 0.55 is row 22 of the stacked image, row 2 of page 1.
    for (Vec2 v : {e.a0, e.a1, e.b0, e.b1}) {
      EXPECT_GE(v.y, 2.0f - 1e-3f);
      EXPECT_LE(v.y, 8.0f + 1e-3f);
    }
  }
}

}  // namespace
}  // namespace luxel::atlas
