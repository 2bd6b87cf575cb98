// generate_lightmap_uvs (uv/generate.h) on hostile input and at extreme
// scales: non-manifold edges, zero-area and duplicate triangles, non-finite
// positions, meshes with nothing to lay out. Every case must end in a clear
// error or a layout with no overlapping texel centre (an independent
// rasteriser, tests/support/uv_layout_check.h), never a crash or a hang (the
// ctest timeout catches a hang).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "support/uv_layout_check.h"
#include "uv/generate.h"
#include "uv_meshes.h"

namespace luxel::uv::testing {
namespace {

scene::Scene scene_of(std::vector<scene::Mesh> meshes) {
  scene::Scene s;
  s.materials.resize(1);
  for (size_t i = 0; i < meshes.size(); ++i) {
    scene::Instance inst;
    inst.name = "node_" + std::to_string(i);
    inst.mesh = static_cast<int>(i);
    s.instances.push_back(inst);
    if (meshes[i].name.empty()) meshes[i].name = "mesh_" + std::to_string(i);
    s.meshes.push_back(std::move(meshes[i]));
  }
  return s;
}

GenerateOptions at_resolution(int side) {
  GenerateOptions o;
  o.atlas.resolution = side;
  return o;
}

// Generates, then checks the layout independently: every triangle inside the
// atlas and no texel centre covered twice.
GeneratedUvs generate_checked(const scene::Scene& s, const GenerateOptions& o) {
  auto r = generate_lightmap_uvs(s, o);
  EXPECT_TRUE(r.is_ok()) << r.status().to_string();
  if (!r) return {};
  const luxel::testing::LayoutCheck check = luxel::testing::check_layout(r->scene, r->atlas);
  EXPECT_EQ(check.overlapping_texels, 0);
  EXPECT_EQ(check.outside_triangles, 0);
  EXPECT_GT(check.covered_texels, 0);
  return std::move(r.value());
}

void expect_invalid(const scene::Scene& s, const GenerateOptions& o, const std::string& needle) {
  auto r = generate_lightmap_uvs(s, o);
  ASSERT_FALSE(r.is_ok()) << "expected an error mentioning '" << needle << "'";
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument) << r.status().to_string();
  EXPECT_NE(r.status().to_string().find(needle), std::string::npos) << r.status().to_string();
}

double uv_area(const scene::Mesh& m, size_t t) {
  const Vec2 a = m.uv1[m.indices[3 * t]], b = m.uv1[m.indices[3 * t + 1]],
             c = m.uv1[m.indices[3 * t + 2]];
  return 0.5 * std::fabs((double(b.x) - a.x) * (double(c.y) - a.y) -
                         (double(c.x) - a.x) * (double(b.y) - a.y));
}

// Four triangles on one edge (a book with four pages), and two fans that
// share only a vertex (a bow tie): not 2-manifold.
TEST(UvGenerateInput, NonManifoldEdgesAndVertices) {
  scene::Mesh m;
  m.name = "book";
  const uint32_t a = add_vertex(m, {0, 0, 0}, {0, 0, 1}), b = add_vertex(m, {0, 1, 0}, {0, 0, 1});
  for (int k = 0; k < 4; ++k) {
    const double ang = 0.3 + k * 1.5;
    const uint32_t c = add_vertex(m, {float(std::cos(ang)), 0.5f, float(std::sin(ang))}, {0, 0, 1});
    add_triangle(m, a, b, c);
  }
  // Bow tie: two triangles meeting at one vertex, then a third page on the
  // first book edge with the opposite winding.
  const uint32_t o = add_vertex(m, {3, 0, 0}, {0, 0, 1});
  add_triangle(m, o, add_vertex(m, {4, 1, 0}, {0, 0, 1}), add_vertex(m, {4, -1, 0}, {0, 0, 1}));
  add_triangle(m, o, add_vertex(m, {2, -1, 0}, {0, 0, 1}), add_vertex(m, {2, 1, 0}, {0, 0, 1}));
  add_triangle(m, b, a, add_vertex(m, {-1, 0.5f, -0.2f}, {0, 0, 1}));
  const GeneratedUvs g = generate_checked(scene_of({m}), at_resolution(128));
  EXPECT_EQ(g.report.triangles, m.triangle_count());
  EXPECT_EQ(g.report.unplaced_triangles, 0u);
  // No more than two triangles can share a chart edge, so the five on edge ab
  // are in at least three charts.
  EXPECT_GE(g.report.charts, 3u);
  for (size_t t = 0; t < m.triangle_count(); ++t) EXPECT_GT(uv_area(g.scene.meshes[0], t), 0);
}

// Repeated-vertex and collinear triangles are skipped and counted; the rest
// of the mesh is laid out as usual.
TEST(UvGenerateInput, ZeroAreaTrianglesAreSkippedAndCounted) {
  scene::Mesh m = grid(4);
  const size_t good = m.triangle_count();
  add_triangle(m, 0, 0, 1);  // repeated vertex
  add_triangle(m, 0, 1, 2);  // collinear (the grid's first row)
  const uint32_t p = add_vertex(m, {9, 9, 1}, {0, 0, 1});
  add_triangle(m, p, p, p);  // a point
  // Collinear corners that are distinct vertices off the grid.
  const uint32_t q0 = add_vertex(m, {0, 0, 2}, {0, 0, 1}), q1 = add_vertex(m, {1, 1, 2}, {0, 0, 1}),
                 q2 = add_vertex(m, {3, 3, 2}, {0, 0, 1});
  add_triangle(m, q0, q1, q2);
  const GeneratedUvs g = generate_checked(scene_of({m}), at_resolution(64));
  EXPECT_EQ(g.report.unplaced_triangles, 4u);
  EXPECT_EQ(g.report.triangles, good + 4);
  // Unplaced triangles collapse to a point: they cover no texel.
  for (size_t t = good; t < good + 4; ++t) EXPECT_EQ(uv_area(g.scene.meshes[0], t), 0);
  for (size_t t = 0; t < good; ++t) EXPECT_GT(uv_area(g.scene.meshes[0], t), 0);
}

TEST(UvGenerateInput, NonFinitePositionIsAnErrorNamingTheMesh) {
  for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                    -std::numeric_limits<float>::infinity()}) {
    scene::Mesh m = sphere(1, 8, 12);
    m.name = "broken_sphere";
    m.positions[5].y = bad;
    expect_invalid(scene_of({grid(2), m}), at_resolution(64), "broken_sphere");
  }
  // A non-finite vertex that no triangle uses is not geometry: fine.
  scene::Mesh m = grid(3);
  add_vertex(m, {std::numeric_limits<float>::quiet_NaN(), 0, 0}, {0, 0, 1});
  generate_checked(scene_of({m}), at_resolution(64));
}

TEST(UvGenerateInput, IndexOutOfRangeIsAnError) {
  scene::Mesh m = grid(2);
  m.name = "bad_index";
  m.indices[4] = 1000;
  expect_invalid(scene_of({m}), at_resolution(64), "bad_index");
}

TEST(UvGenerateInput, OnlyDegenerateTriangles) {
  scene::Mesh m;
  m.name = "flat_line";
  for (int k = 0; k < 10; ++k) {
    const uint32_t a = add_vertex(m, {float(k), 0, 0}, {0, 0, 1});
    const uint32_t b = add_vertex(m, {float(k) + 1, 0, 0}, {0, 0, 1});
    const uint32_t c = add_vertex(m, {float(k) + 2, 0, 0}, {0, 0, 1});
    add_triangle(m, a, b, c);
    add_triangle(m, a, a, b);
  }
  // Alone: nothing to lay out is an error, at a resolution and at a density.
  expect_invalid(scene_of({m}), at_resolution(64), "no triangle");
  GenerateOptions by_density;
  by_density.atlas.texel_density = 4;
  expect_invalid(scene_of({m}), by_density, "no triangle");
  // Beside a real mesh: skipped, covering no texel. (UvReport counts only
  // the degenerate triangles of meshes that have a chart: this mesh's 20 are
  // in neither `triangles` nor `unplaced_triangles`.)
  const GeneratedUvs g = generate_checked(scene_of({grid(3), m}), at_resolution(64));
  for (size_t t = 0; t < m.triangle_count(); ++t) EXPECT_EQ(uv_area(g.scene.meshes[1], t), 0);
  // A mesh without any triangle beside a real one.
  scene::Mesh empty;
  empty.name = "empty";
  generate_checked(scene_of({grid(3), empty}), at_resolution(64));
}

// A mesh whose triangles are all zero-area, with a TEXCOORD_1 that has UV
// area: generation collapses its UVs (found when such a mesh kept the file's
// UVs over texels that generated charts own).
TEST(UvGenerateInput, AllDegenerateMeshWithFileUvsCoversNoTexel) {
  scene::Mesh m;
  m.name = "degenerate_with_uvs";
  const uint32_t a = add_vertex(m, {0, 0, 0}, {0, 0, 1}), b = add_vertex(m, {1, 0, 0}, {0, 0, 1}),
                 c = add_vertex(m, {2, 0, 0}, {0, 0, 1});
  m.uv1 = {{0, 0}, {1, 0}, {1, 1}};
  add_triangle(m, a, b, c);
  generate_checked(scene_of({grid(3), m}), at_resolution(64));
}

// One mesh used by two instances whose sizes differ by `ratio`. When the
// mesh's layout was packed at the smallest instance's size and scaled up
// for the larger one, padding and mask rounding included: at 100 the 256^2
// atlas was RESOURCE_EXHAUSTED at every density tried, at 1e6 the first
// probe threw std::bad_alloc, and at 1e18 (found by import_fuzz) the UVs
// collapsed to one point outside the atlas. The layout is now packed at no
// less than a quarter of the largest instance's size (MeshCharts::kMaxGrow).
TEST(UvGenerateInput, InstancesOfVeryDifferentSizes) {
  for (double ratio : {100.0, 1e6, 1e18}) {
    SCOPED_TRACE(ratio);
    scene::Scene s = scene_of({sphere(1, 6, 8)});
    scene::Instance big = s.instances[0];
    for (int a = 0; a < 3; ++a) big.object_to_world.at(a, a) = ratio;
    s.instances.push_back(big);
    generate_checked(s, at_resolution(256));
  }
}

// One sliver 3426 units long and 0.0006 wide (found by import_fuzz). At a
// fixed 64^2 the answer is a density at which it is ~58 texels long; a first
// probe whose density came from the area alone (52 texels per unit) with no
// limit on the automatic atlas side asked the packer for a ~178,000^2-bit
// mask (4 GB). The probe's density is now bounded by the longest shape and
// its atlas side by 16x the requested one.
TEST(UvGenerateInput, LongSliverAtAFixedResolution) {
  scene::Mesh m;
  add_triangle(m, add_vertex(m, {0, 3426.12f, 0}, {1, 0, 0}), add_vertex(m, {0, 0, 0}, {1, 0, 0}),
               add_vertex(m, {0.000619492f, 12.2078f, 0}, {1, 0, 0}));
  generate_checked(scene_of({m}), at_resolution(64));
}

// A mesh used by two instances with a triangle whose smallest angle is below
// the chart builder's zero-area test (found by import_fuzz): it once
// collapsed onto uv1 = (0, 0) of the mesh's own layout, which the second
// instance's scale and offset put outside the atlas; it now collapses onto
// a point of the first chart.
TEST(UvGenerateInput, DegenerateTriangleOfAnInstancedMeshStaysInTheAtlas) {
  scene::Mesh m = sphere(1, 6, 8);
  add_triangle(m, add_vertex(m, {0, 0, 2}, {0, 0, 1}), add_vertex(m, {1, 0, 2}, {0, 0, 1}),
               add_vertex(m, {2, 1e-10f, 2}, {0, 0, 1}));
  scene::Scene s = scene_of({m});
  scene::Instance other = s.instances[0];
  other.object_to_world.at(0, 3) = 8;
  for (int a = 0; a < 3; ++a) other.object_to_world.at(a, a) = 2;
  s.instances.push_back(other);
  const GeneratedUvs g = generate_checked(s, at_resolution(64));
  EXPECT_GT(g.report.unplaced_triangles, 0u);
  const luxel::testing::LayoutCheck check = luxel::testing::check_layout(g.scene, g.atlas);
  EXPECT_EQ(check.outside_points, 0);
}

// The same triangle twice over the same vertices, twice over coincident
// copies of them, and back to back: each copy needs its own texels.
TEST(UvGenerateInput, DuplicateAndBackToBackTriangles) {
  scene::Mesh m = grid(3);
  const size_t n = m.triangle_count();
  for (size_t t = 0; t < n; ++t)
    add_triangle(m, m.indices[3 * t], m.indices[3 * t + 1], m.indices[3 * t + 2]);
  for (size_t t = 0; t < n; ++t) {
    uint32_t v[3];
    for (int k = 0; k < 3; ++k) {
      const uint32_t i = m.indices[3 * t + static_cast<size_t>(k)];
      v[k] = add_vertex(m, m.positions[i], m.normals[i]);
    }
    add_triangle(m, v[0], v[1], v[2]);
    add_triangle(m, v[0], v[2], v[1]);  // back to back
  }
  const GeneratedUvs g = generate_checked(scene_of({m}), at_resolution(128));
  EXPECT_EQ(g.report.unplaced_triangles, 0u);
  EXPECT_EQ(g.report.triangles, 4 * n);
  for (size_t t = 0; t < 4 * n; ++t) EXPECT_GT(uv_area(g.scene.meshes[0], t), 0) << t;
}

// Long slivers (aspect 1e6): each is one chart of its own shape.
TEST(UvGenerateInput, Slivers) {
  scene::Mesh m;
  for (int k = 0; k < 20; ++k) {
    const float y = float(k);
    add_triangle(m, add_vertex(m, {0, y, 0}, {0, 0, 1}), add_vertex(m, {1, y, 0}, {0, 0, 1}),
                 add_vertex(m, {0.5f, y + 1e-6f * (1 + y), 0}, {0, 0, 1}));
  }
  const GeneratedUvs g = generate_checked(scene_of({m}), at_resolution(256));
  EXPECT_EQ(g.report.triangles, m.triangle_count());
  EXPECT_EQ(g.report.unplaced_triangles, 0u);
}

// Unit triangles in a mesh that also has a part 1e6 units away. Vertices are
// welded within weld_relative_epsilon (1e-6) of the mesh's bounding-box
// diagonal (charts.h, step 1), here 1.4 units, so with the default the unit
// triangles collapse and nothing is left to lay out: recorded, not hidden.
// With welding of identical positions only (epsilon 0) every triangle is
// laid out.
TEST(UvGenerateInput, FarPartsOfOneMesh) {
  scene::Mesh m = grid(3);
  const uint32_t f = add_vertex(m, {1e6f, 1e6f, 0}, {0, 0, 1});
  add_triangle(m, f, add_vertex(m, {1e6f + 1, 1e6f, 0}, {0, 0, 1}),
               add_vertex(m, {1e6f, 1e6f + 1, 0}, {0, 0, 1}));
  auto collapsed = generate_lightmap_uvs(scene_of({m}), at_resolution(64));
  ASSERT_TRUE(collapsed.is_ok()) << collapsed.status().to_string();
  // Measured: 17 of the 19 triangles are unplaced (skipped as zero-area after
  // welding), and the layout is still overlap-free.
  EXPECT_GT(collapsed->report.unplaced_triangles, 0u)
      << "the default weld keeps unit triangles 1e6 units from the origin now: expect 0 here";
  const luxel::testing::LayoutCheck check =
      luxel::testing::check_layout(collapsed->scene, collapsed->atlas);
  EXPECT_EQ(check.overlapping_texels, 0);
  GenerateOptions exact = at_resolution(64);
  exact.charts.weld_relative_epsilon = 0;
  const GeneratedUvs g = generate_checked(scene_of({m}), exact);
  EXPECT_EQ(g.report.unplaced_triangles, 0u);
  EXPECT_EQ(g.report.triangles, m.triangle_count());
}

// The same scene with positions scaled by s and texel density by 1/s
// (DESIGN.md: scenes from 1e-3 to 1e5 units).
scene::Scene scale_scene(float s) {
  scene::Mesh wall = scaled(l_wall(4, 0.3f, 2, 3), s);
  scene::Mesh ball = scaled(sphere(1, 12, 16), s);
  for (Vec3& p : ball.positions) p.x += 6 * s;
  return scene_of({wall, scaled(torus(1.5f, 0.5f, 16, 12), s), ball});
}

constexpr float kScaleDensity = 12;  // texels per unit at scale 1: a 148^2 atlas

// Largest |uv1 difference| over all vertices, in texels.
double worst_uv_texels(const GeneratedUvs& a, const GeneratedUvs& b) {
  double worst = 0;
  for (size_t m = 0; m < a.scene.meshes.size(); ++m) {
    const auto& x = a.scene.meshes[m].uv1;
    const auto& y = b.scene.meshes[m].uv1;
    if (x.size() != y.size()) return INFINITY;
    for (size_t v = 0; v < x.size(); ++v)
      worst = std::max({worst, std::fabs(double(x[v].x) - y[v].x) * a.atlas.width,
                        std::fabs(double(x[v].y) - y[v].y) * a.atlas.height});
  }
  return worst;
}

// Positions scaled by 1e-3 and 1e4 (and by the powers of two near them,
// which change no rounding) with the texel density scaled by 1/s, or the
// same resolution: the same charts, atlas and UVs. Measured: UVs equal to
// 9e-6 texel at 1e-3 and 1e4.
TEST(UvGenerateInput, ExtremeScaleGivesTheSameLayout) {
  for (bool fixed : {false, true}) {
    SCOPED_TRACE(fixed ? "at a resolution" : "at a density");
    GenerateOptions o;
    o.atlas.texel_density = kScaleDensity;
    const GeneratedUvs ref = generate_checked(scale_scene(1), o);
    ASSERT_GT(ref.atlas.width, 0);
    for (float s : {1e-3f, 1e4f, 0x1p-10f, 0x1p13f}) {
      SCOPED_TRACE(s);
      GenerateOptions os = fixed ? at_resolution(ref.atlas.width) : GenerateOptions{};
      if (!fixed) os.atlas.texel_density = kScaleDensity / s;
      const GeneratedUvs want = fixed ? generate_checked(scale_scene(1), os) : ref;
      const GeneratedUvs got = generate_checked(scale_scene(s), os);
      EXPECT_EQ(got.report.charts, want.report.charts);
      EXPECT_EQ(got.report.seam_vertices, want.report.seam_vertices);
      ASSERT_EQ(got.atlas.width, want.atlas.width);
      ASSERT_EQ(got.atlas.height, want.atlas.height);
      EXPECT_NEAR(got.atlas.texels_per_unit * s, want.atlas.texels_per_unit,
                  1e-6 * want.atlas.texels_per_unit);
      EXPECT_LE(worst_uv_texels(got, want), 1e-3);
    }
  }
}

// The torus built again at 1e-3 and 1e4 (its vertices computed at that size,
// so they differ from the scaled ones by float rounding, ~1e-7 relative).
// Charts follow to that precision, but the packer's conservative texel masks
// and its order (size bucket, then covered texels) are discrete, so a chart
// may land elsewhere: the layout is equivalent, not equal. Measured: same
// charts and atlas side, efficiency within 0.1 %, UVs up to ~120 texels apart.
TEST(UvGenerateInput, RebuiltAtExtremeScaleGivesAnEquivalentLayout) {
  auto rebuilt = [](float s) {
    scene::Scene sc = scale_scene(s);
    sc.meshes[1] = torus(1.5f * s, 0.5f * s, 16, 12);
    return sc;
  };
  GenerateOptions o;
  o.atlas.texel_density = kScaleDensity;
  const GeneratedUvs ref = generate_checked(rebuilt(1), o);
  for (float s : {1e-3f, 1e4f}) {
    SCOPED_TRACE(s);
    GenerateOptions os;
    os.atlas.texel_density = kScaleDensity / s;
    const GeneratedUvs got = generate_checked(rebuilt(s), os);
    EXPECT_EQ(got.report.charts, ref.report.charts);
    EXPECT_EQ(got.report.seam_vertices, ref.report.seam_vertices);
    EXPECT_EQ(got.atlas.width, ref.atlas.width);
    EXPECT_EQ(got.atlas.height, ref.atlas.height);
    EXPECT_NEAR(got.report.efficiency, ref.report.efficiency, 0.01);
    EXPECT_NEAR(got.report.stretch_l2, ref.report.stretch_l2, 1e-5);
    EXPECT_NEAR(got.report.stretch_linf, ref.report.stretch_linf, 1e-4);
    const luxel::testing::LayoutCheck a = luxel::testing::check_layout(got.scene, got.atlas);
    const luxel::testing::LayoutCheck b = luxel::testing::check_layout(ref.scene, ref.atlas);
    EXPECT_NEAR(a.stretch_l2, b.stretch_l2, 1e-4);
    EXPECT_NEAR(static_cast<double>(a.covered_texels), static_cast<double>(b.covered_texels),
                0.01 * static_cast<double>(b.covered_texels));
  }
}

}  // namespace
}  // namespace luxel::uv::testing
