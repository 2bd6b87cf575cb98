// The chart validator against injected defects, and the stretch metric
// (Sander et al. 2001) against closed forms.
#include <gtest/gtest.h>

#include <cmath>

#include "uv/charts.h"
#include "uv/stretch.h"
#include "uv/validate.h"
#include "uv_meshes.h"

namespace luxel::uv::testing {
namespace {

// The largest LSCM chart of a sphere: a curved chart with interior vertices.
Chart sphere_chart(scene::Mesh* mesh_out) {
  *mesh_out = sphere(1.0f, 16, 32);
  auto charts = build_charts(*mesh_out).value();
  size_t best = 0;
  for (size_t i = 0; i < charts.size(); ++i)
    if (charts[i].triangles.size() > charts[best].triangles.size()) best = i;
  return charts[best];
}

TEST(UvValidate, AcceptsProducedChart) {
  scene::Mesh m;
  const Chart c = sphere_chart(&m);
  ASSERT_GT(c.triangles.size(), 10u);
  EXPECT_EQ(validate_chart(c), ChartDefect::kNone);
}

TEST(UvValidate, RejectsAFlippedTriangle) {
  scene::Mesh m;
  Chart c = sphere_chart(&m);
  std::swap(c.indices[3 * 4 + 1], c.indices[3 * 4 + 2]);
  EXPECT_EQ(validate_chart(c), ChartDefect::kFlipped);
}

TEST(UvValidate, RejectsAFoldedVertex) {
  // Move an interior vertex across the far side of its fan: the triangles on
  // the near side flip.
  scene::Mesh m;
  Chart c = sphere_chart(&m);
  // A vertex used by six triangles is interior in this chart.
  std::vector<int> uses(c.vertices.size(), 0);
  for (uint32_t i : c.indices) ++uses[i];
  size_t v = 0;
  while (v < uses.size() && uses[v] < 6) ++v;
  ASSERT_LT(v, uses.size());
  Vec2 far{0, 0};
  for (size_t t = 0; t < c.indices.size(); t += 3)
    for (int j = 0; j < 3; ++j)
      if (c.indices[t + j] == v) {
        const Vec2 q = c.uv[c.indices[t + (j + 1) % 3]];
        far = {q.x + (q.x - c.uv[v].x) * 3, q.y + (q.y - c.uv[v].y) * 3};
      }
  c.uv[v] = far;
  EXPECT_EQ(validate_chart(c), ChartDefect::kFlipped);
}

TEST(UvValidate, RejectsZeroAreaAndNonFinite) {
  scene::Mesh m;
  Chart c = sphere_chart(&m);
  Chart z = c;
  z.uv[z.indices[0]] = z.uv[z.indices[1]];  // collapse an edge of triangle 0
  EXPECT_EQ(validate_chart(z), ChartDefect::kZeroArea);
  Chart n = c;
  n.uv[3].y = NAN;
  EXPECT_EQ(validate_chart(n), ChartDefect::kNonFinite);
}

TEST(UvValidate, RejectsCrossingBoundaries) {
  // Two counter-clockwise triangles with no shared vertex whose edges cross:
  // no triangle is flipped, only the boundary test can see the overlap.
  const std::vector<Vec2> uv = {{0, 0}, {2, 0}, {0, 2}, {1, 1.5f}, {1, -1}, {3, 1}};
  const std::vector<uint32_t> idx = {0, 1, 2, 3, 4, 5};
  EXPECT_EQ(find_chart_defect(uv, idx), ChartDefect::kBoundaryCrossing);
  // Moved apart, the same pair is fine.
  std::vector<Vec2> apart = uv;
  for (size_t i = 3; i < 6; ++i) apart[i].x += 10;
  EXPECT_EQ(find_chart_defect(apart, idx), ChartDefect::kNone);
}

TEST(UvStretch, PlanarQuadHasNoStretch) {
  // Closed form: an axis-aligned quad projects exactly, so L2 = Linf = 1.
  scene::Mesh m;
  add_flat_quad(m, {0, 0, 0}, {2, 0, 0}, {2, 1, 0}, {0, 1, 0});
  auto charts = build_charts(m).value();
  ASSERT_EQ(charts.size(), 1u);
  const Stretch s = chart_stretch(m, charts[0]);
  EXPECT_DOUBLE_EQ(s.l2, 1.0);
  EXPECT_DOUBLE_EQ(s.linf, 1.0);
  EXPECT_DOUBLE_EQ(s.area_uv, 2.0);
  // Tilted and far from the origin: exact up to float rounding.
  scene::Mesh t;
  const Vec3 o{100, -50, 20}, a = normalize(Vec3{1, 2, 3}) * 3.0f;
  const Vec3 b = normalize(cross(a, Vec3{0, 0, 1})) * 0.5f;
  add_flat_quad(t, o, o + a, o + a + b, o + b);
  const Stretch st = mesh_stretch(t, build_charts(t).value());
  EXPECT_NEAR(st.l2, 1.0, 1e-5);
  EXPECT_NEAR(st.linf, 1.0, 1e-5);
}

TEST(UvStretch, AnisotropicScaleClosedForm) {
  // UV = 3D triangle with u doubled: dq/ds = 1/2 and dq/dt = 1, so
  // L2 = sqrt((1/4 + 1)/2), Linf = 1; normalised by sqrt(A_uv / A_3d) = sqrt(2).
  const DVec3 q[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const Vec2 p[3] = {{0, 0}, {2, 0}, {0, 1}};
  const Stretch s = triangle_stretch(q, p);
  EXPECT_NEAR(s.l2, std::sqrt(0.625), 1e-12);
  EXPECT_NEAR(s.linf, 1.0, 1e-12);
  EXPECT_NEAR(s.area_uv, 1.0, 1e-12);

  scene::Mesh m;
  const uint32_t a = add_vertex(m, {0, 0, 0}, {0, 0, 1}), b = add_vertex(m, {1, 0, 0}, {0, 0, 1}),
                 c = add_vertex(m, {0, 1, 0}, {0, 0, 1});
  add_triangle(m, a, b, c);
  Chart chart;
  chart.triangles = {0};
  chart.vertices = {a, b, c};
  chart.indices = {0, 1, 2};
  chart.uv = {p[0], p[1], p[2]};
  const Stretch cs = chart_stretch(m, chart);
  EXPECT_NEAR(cs.l2, std::sqrt(0.625) * std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(cs.linf, std::sqrt(2.0), 1e-12);
  // A uniform UV scale is normalised away.
  for (Vec2& v : chart.uv) v = {v.x * 8, v.y * 8};
  EXPECT_NEAR(chart_stretch(m, chart).l2, cs.l2, 1e-12);
}

}  // namespace
}  // namespace luxel::uv::testing
