// Light sampling on the device (kernels/shading/lights.h, PoCL): sampled
// directions follow the pdf the sampler reports (chi-square over solid-angle
// cells), the MIS pdf agrees with the sampler, selection follows power.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "shading_probe.h"
#include "support/chi2.h"
#include "test_scenes.h"

namespace luxel::pipeline {
namespace {

using test::Rng;
using test::SceneBuilder;

constexpr double kPi = 3.14159265358979323846;
// Chi-square tests in this binary (light_sampling_test + sky_test), 1%
// family-wise false-failure rate (sky_test runs its chi-square for two normals).
const double kAlpha = test_support::sidak_alpha(0.01, 5);

struct D3 {
  double x, y, z;
};
D3 d3(Vec3 v) {
  return {v.x, v.y, v.z};
}
D3 d3(const cl::float4& v) {
  return {v.x, v.y, v.z};
}
D3 operator-(D3 a, D3 b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
D3 operator+(D3 a, D3 b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
D3 operator*(D3 a, double s) {
  return {a.x * s, a.y * s, a.z * s};
}
double dot(D3 a, D3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
D3 cross(D3 a, D3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
D3 unit(D3 a) {
  return a * (1 / std::sqrt(dot(a, a)));
}

// Spherical cells around an axis: h = 1 - cos(theta) in [0, h_max) split in
// `rows`, phi in `cols`; h and phi of a direction computed from the
// perpendicular part so tiny cones (the sun) keep their precision.
struct ConeGrid {
  D3 axis, t, b;
  double h_max;
  int rows, cols;

  ConeGrid(D3 axis_in, double h_max_in, int rows_in, int cols_in)
      : axis(unit(axis_in)), h_max(h_max_in), rows(rows_in), cols(cols_in) {
    const D3 helper = std::fabs(axis.x) < 0.9 ? D3{1, 0, 0} : D3{0, 1, 0};
    t = unit(cross(helper, axis));
    b = cross(axis, t);
  }
  // Cell index, or -1 outside [0, h_max).
  int cell(D3 dir) const {
    const double along = dot(dir, axis), px = dot(dir, t), py = dot(dir, b);
    const double theta = std::atan2(std::sqrt(px * px + py * py), along);
    const double h = 2 * std::sin(theta / 2) * std::sin(theta / 2);
    if (!(h < h_max)) return -1;
    double phi = std::atan2(py, px);
    if (phi < 0) phi += 2 * kPi;
    const int r = std::min(static_cast<int>(h / h_max * rows), rows - 1);
    const int c = std::min(static_cast<int>(phi / (2 * kPi) * cols), cols - 1);
    return r * cols + c;
  }
  // Direction at fractional cell coordinates (row + fr, col + fc).
  D3 dir(double row, double col) const {
    const double h = row / rows * h_max, phi = col / cols * 2 * kPi;
    const double sin_t = std::sqrt(std::max(h * (2 - h), 0.0));
    return unit(t * (std::cos(phi) * sin_t) + b * (std::sin(phi) * sin_t) + axis * (1 - h));
  }
  double cell_solid_angle() const { return h_max / rows * 2 * kPi / cols; }
  size_t size() const { return static_cast<size_t>(rows * cols); }
};

std::vector<cl::float4> randoms(size_t n, uint64_t seed) {
  Rng rng(seed);
  std::vector<cl::float4> r(n);
  for (auto& v : r) v = rng.uniform4();
  return r;
}

// Host ray / triangle intersection in double: the point where `dir` from p
// meets the triangle, if it does.
bool hit_triangle(D3 p, D3 dir, D3 v0, D3 v1, D3 v2, D3* hit) {
  const D3 e1 = v1 - v0, e2 = v2 - v0, s = p - v0, q = cross(dir, e2);
  const double det = dot(e1, q);
  if (std::fabs(det) < 1e-300) return false;
  const double u = dot(s, q) / det;
  const D3 r = cross(s, e1);
  const double v = dot(dir, r) / det, t = dot(e2, r) / det;
  if (u < 0 || v < 0 || u + v > 1 || t <= 0) return false;
  *hit = p + dir * t;
  return true;
}

struct CellIntegral {
  std::vector<double> probability;  // integral of the pdf over each cell
  std::vector<double> coverage;     // fraction of sub-cells whose direction hits the triangle
};

std::vector<int> all_cells(const ConeGrid& grid) {
  std::vector<int> cells(grid.size());
  for (size_t i = 0; i < cells.size(); ++i) cells[i] = int(i);
  return cells;
}

// Midpoint rule with `sub` x `sub` sub-cells over the listed cells of the
// device's lux_light_pdf_triangle (light 0) seen from p.
Result<CellIntegral> integrate_triangle_pdf(test::LightProbe& probe, const ConeGrid& grid, D3 p,
                                            const std::array<D3, 3>& tri,
                                            const std::vector<int>& cells, int sub) {
  std::vector<int> light;
  std::vector<cl::float4> pts, hits, normals;
  std::vector<size_t> cell_of;
  const D3 n_geo = cross(tri[1] - tri[0], tri[2] - tri[0]);
  auto f = [](D3 v) { return cl::float4{float(v.x), float(v.y), float(v.z), 0}; };
  for (int cell : cells) {
    const int r = cell / grid.cols, c = cell % grid.cols;
    for (int i = 0; i < sub; ++i)
      for (int j = 0; j < sub; ++j) {
        D3 hit;
        if (!hit_triangle(p, grid.dir(r + (i + 0.5) / sub, c + (j + 0.5) / sub), tri[0], tri[1],
                          tri[2], &hit))
          continue;
        light.push_back(0);
        pts.push_back(f(p));
        hits.push_back(f(hit));
        normals.push_back(f(n_geo));
        cell_of.push_back(size_t(cell));
      }
  }
  CellIntegral out;
  out.probability.assign(grid.size(), 0.0);
  out.coverage.assign(grid.size(), 0.0);
  if (light.empty()) return out;
  auto pdf = probe.triangle_pdf(light, pts, hits, normals);
  if (!pdf) return pdf.status();
  const double weight = grid.cell_solid_angle() / (sub * sub);
  for (size_t k = 0; k < cell_of.size(); ++k) {
    out.probability[cell_of[k]] += (*pdf)[k] * weight;
    out.coverage[cell_of[k]] += 1.0 / (sub * sub);
  }
  return out;
}

TEST(LightSampling, EmissiveTriangleDirectionsFollowTheirPdf) {
  SceneBuilder b;
  const int glow = b.add_emitter({1, 1, 1});
  const Vec3 v0{-1, 2, -0.5f}, v1{1.5f, 2.5f, 0}, v2{0, 1.5f, 1.5f};
  b.add_triangles({v0, v1, v2}, glow);  // winding: normal faces down, towards p
  auto table = build_light_table(b.s, b.soup(), {}, Bounds3{});
  ASSERT_TRUE(table.is_ok()) << table.status().to_string();
  auto probe = test::LightProbe::create(table.value());
  ASSERT_TRUE(probe.is_ok()) << probe.status().to_string();

  const Vec3 p{0.1f, 0.2f, 0.3f};
  const size_t n = 400000;
  auto s = (*probe)->sample_at(p, randoms(n, 2));
  ASSERT_TRUE(s.is_ok()) << s.status().to_string();
  const D3 centroid = (d3(v0) + d3(v1) + d3(v2)) * (1.0 / 3);
  const ConeGrid grid(centroid - d3(p), 0.3, 12, 24);
  std::vector<double> observed(grid.size());
  for (size_t i = 0; i < n; ++i) {
    ASSERT_TRUE(s->ok(i)) << "p sees the front of the emitter: every sample counts";
    ASSERT_FALSE(s->is_delta(i));
    ASSERT_TRUE(s->mis(i));
    const int c = grid.cell(d3(s->wi_pdf[i]));
    ASSERT_GE(c, 0) << "sample outside the grid: enlarge h_max";
    observed[static_cast<size_t>(c)] += 1;
  }

  // Expected counts: the device MIS pdf integrated over each cell (midpoint
  // rule; directions that miss the triangle count 0). Cells the triangle's
  // edge crosses, or may graze, are integrated again 8x finer.
  const std::array<D3, 3> tri = {d3(v0), d3(v1), d3(v2)};
  auto coarse = integrate_triangle_pdf(**probe, grid, d3(p), tri, all_cells(grid), 16);
  ASSERT_TRUE(coarse.is_ok()) << coarse.status().to_string();
  std::vector<int> edge_cells;
  for (int r = 0; r < grid.rows; ++r)
    for (int c = 0; c < grid.cols; ++c) {
      const auto covered = [&](int rr, int cc) {
        rr = std::clamp(rr, 0, grid.rows - 1);  // rows wrap at neither end
        return coarse->coverage[size_t(rr * grid.cols + (cc + grid.cols) % grid.cols)];
      };
      bool edge = covered(r, c) > 0 && covered(r, c) < 1;
      for (int dr = -1; dr <= 1; ++dr)
        for (int dc = -1; dc <= 1; ++dc)
          edge = edge || (covered(r + dr, c + dc) > 0) != (covered(r, c) > 0);
      if (edge) edge_cells.push_back(r * grid.cols + c);
    }
  auto fine = integrate_triangle_pdf(**probe, grid, d3(p), tri, edge_cells, 128);
  ASSERT_TRUE(fine.is_ok()) << fine.status().to_string();
  std::vector<double> expected(grid.size());
  double total = 0;
  for (size_t k = 0; k < grid.size(); ++k) {
    const bool refined =
        std::find(edge_cells.begin(), edge_cells.end(), int(k)) != edge_cells.end();
    expected[k] = n * (refined ? fine->probability[k] : coarse->probability[k]);
    total += expected[k];
  }
  EXPECT_NEAR(total / n, 1.0, 1e-3) << "the pdf integrates to 1 over the triangle's solid angle";
  const auto chi2 = test_support::chi2_test(observed, expected, kAlpha);
  EXPECT_GT(chi2.p_value, kAlpha) << chi2.detail;
}

TEST(LightSampling, SunDiscDirectionsAreUniformInItsCone) {
  LightSettings settings;
  settings.sun.enabled = true;
  settings.sun.direction = {0.3f, -1, 0.2f};
  settings.sun.angular_radius_degrees = 0.27f;
  auto table = build_light_table(scene::Scene{}, accel::TriangleSoup{}, settings, Bounds3{});
  ASSERT_TRUE(table.is_ok()) << table.status().to_string();
  auto probe = test::LightProbe::create(table.value());
  ASSERT_TRUE(probe.is_ok()) << probe.status().to_string();
  const size_t n = 200000;
  auto s = (*probe)->sample_at({0, 0, 0}, randoms(n, 2));
  ASSERT_TRUE(s.is_ok()) << s.status().to_string();

  const double a = 0.27 * kPi / 180, h_cone = 1 - std::cos(a);
  // 8 rows inside the cone, 4 outside that must stay empty.
  const ConeGrid grid(D3{-0.3, 1, -0.2}, 1.5 * h_cone, 12, 16);
  std::vector<double> observed(grid.size()), expected(grid.size());
  for (int r = 0; r < 8; ++r)
    for (int c = 0; c < grid.cols; ++c)
      expected[static_cast<size_t>(r * grid.cols + c)] = double(n) / (8 * 16);
  for (size_t i = 0; i < n; ++i) {
    ASSERT_TRUE(s->ok(i));
    ASSERT_FALSE(s->is_delta(i)) << "a disc, not a delta";
    ASSERT_FALSE(s->mis(i)) << "escaping rays do not see the sun: NEE is its only estimator";
    ASSERT_EQ(s->radiance_dist[i].w, INFINITY);
    ASSERT_NEAR(s->wi_pdf[i].w * 2 * kPi * h_cone, 1.0, 1e-4);
    const int c = grid.cell(d3(s->wi_pdf[i]));
    ASSERT_GE(c, 0) << "sample outside 1.5x the cone";
    observed[static_cast<size_t>(c)] += 1;
  }
  const auto chi2 = test_support::chi2_test(observed, expected, kAlpha);
  EXPECT_GT(chi2.p_value, kAlpha) << chi2.detail;
}

// A table with every kind of light, for the consistency and selection tests.
struct MixedScene {
  SceneBuilder b;
  std::vector<std::array<Vec3, 3>> tris;
  MixedScene() {
    b.add_point({0, 3, 0}, {1, 1, 1}, 2.0f);
    b.add_spot({1, 3, 0}, {0, -1, 0}, {1, 1, 1}, 30.0f, 0.3f, 0.5f);
    b.add_directional({0.2f, -1, 0}, {1, 1, 1}, 0.5f);
    const int one = b.add_emitter({3, 2, 1});
    const int two = b.add_emitter({1, 1, 1}, true);
    tris = {{Vec3{-1, 2, -1}, Vec3{-1, 2, 1}, Vec3{1, 2, -1}},
            {Vec3{2, 0, -1}, Vec3{2, 2, -1}, Vec3{2, 0, 1}},
            {Vec3{-2, 0.5f, 0}, Vec3{-3, 1.5f, 1}, Vec3{-2, 2.5f, -1}}};
    b.add_triangles({tris[0][0], tris[0][1], tris[0][2]}, one);
    b.add_triangles({tris[1][0], tris[1][1], tris[1][2], tris[2][0], tris[2][1], tris[2][2]}, two);
  }
};

TEST(LightSampling, TrianglePdfForMisMatchesTheSampledPdf) {
  MixedScene m;
  LightSettings settings;
  settings.sky.kind = SkySettings::Kind::kConstant;
  auto table = build_light_table(m.b.s, m.b.soup(), settings, Bounds3{});
  ASSERT_TRUE(table.is_ok()) << table.status().to_string();
  auto probe = test::LightProbe::create(table.value());
  ASSERT_TRUE(probe.is_ok()) << probe.status().to_string();

  // Points on both sides of the emitters.
  Rng rng(3);
  const size_t n = 20000;
  std::vector<cl::float4> pts(n);
  for (auto& p : pts) p = {rng.uniform() * 4 - 2, rng.uniform() * 4 - 1, rng.uniform() * 4 - 2, 0};
  auto s = (*probe)->sample(pts, randoms(n, 4));
  ASSERT_TRUE(s.is_ok()) << s.status().to_string();
  std::vector<int> light;
  std::vector<cl::float4> p, hit, normal;
  std::vector<float> sampled;
  size_t triangle_samples = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!s->ok(i) || s->info[i].y < 0) continue;
    ++triangle_samples;
    const int tri = s->info[i].y;
    ASSERT_EQ(table->triangle_light[static_cast<size_t>(tri)], s->info[i].x);
    const auto& v = m.tris[static_cast<size_t>(tri)];
    // The sampled point from the barycentrics, and from wi * dist: the same.
    const D3 from_bary =
        d3(v[0]) + (d3(v[1]) - d3(v[0])) * s->bary[i].x + (d3(v[2]) - d3(v[0])) * s->bary[i].y;
    const D3 from_ray = d3(pts[i]) + d3(s->wi_pdf[i]) * s->radiance_dist[i].w;
    ASSERT_LT(std::sqrt(dot(from_bary - from_ray, from_bary - from_ray)), 1e-4);
    const D3 ng = cross(d3(v[1]) - d3(v[0]), d3(v[2]) - d3(v[0]));
    // Grazing samples amplify float rounding in cos; they say nothing here.
    if (std::fabs(dot(unit(ng), d3(s->wi_pdf[i]))) < 0.05) continue;
    light.push_back(s->info[i].x);
    p.push_back(pts[i]);
    hit.push_back({float(from_bary.x), float(from_bary.y), float(from_bary.z), 0});
    normal.push_back({float(-ng.x), float(-ng.y), float(-ng.z), 0});  // either sign is accepted
    sampled.push_back(s->wi_pdf[i].w);
  }
  ASSERT_GT(triangle_samples, n / 10);
  auto pdf = (*probe)->triangle_pdf(light, p, hit, normal);
  ASSERT_TRUE(pdf.is_ok()) << pdf.status().to_string();
  for (size_t k = 0; k < sampled.size(); ++k)
    ASSERT_NEAR((*pdf)[k] / sampled[k], 1.0, 1e-3) << "query " << k;

  // Seen from behind, the one-sided emitter (triangle 0, front +Y by its
  // winding) has pdf 0; the double-sided one (triangle 1) does not.
  const D3 n0 = cross(d3(m.tris[0][1]) - d3(m.tris[0][0]), d3(m.tris[0][2]) - d3(m.tris[0][0]));
  const D3 c0 = (d3(m.tris[0][0]) + d3(m.tris[0][1]) + d3(m.tris[0][2])) * (1.0 / 3);
  const D3 front = c0 + unit(n0), back = c0 - unit(n0);
  const D3 n1 = cross(d3(m.tris[1][1]) - d3(m.tris[1][0]), d3(m.tris[1][2]) - d3(m.tris[1][0]));
  const D3 c1 = (d3(m.tris[1][0]) + d3(m.tris[1][1]) + d3(m.tris[1][2])) * (1.0 / 3);
  auto f = [](D3 v) { return cl::float4{float(v.x), float(v.y), float(v.z), 0}; };
  auto sides = (*probe)->triangle_pdf(
      {table->triangle_light[0], table->triangle_light[0], table->triangle_light[1],
       table->triangle_light[1], -1},
      {f(front), f(back), f(c1 + unit(n1)), f(c1 - unit(n1)), f(front)},
      {f(c0), f(c0), f(c1), f(c1), f(c0)}, {f(n0), f(n0), f(n1), f(n1), f(n0)});
  ASSERT_TRUE(sides.is_ok());
  EXPECT_GT((*sides)[0], 0.0f);
  EXPECT_EQ((*sides)[1], 0.0f) << "back of a one-sided emitter";
  EXPECT_GT((*sides)[2], 0.0f);
  EXPECT_FLOAT_EQ((*sides)[3], (*sides)[2]) << "double-sided: both faces alike";
  EXPECT_EQ((*sides)[4], 0.0f) << "light -1 (not an emitter)";
}

TEST(LightSampling, LightsAreChosenWithTheirSelectionProbability) {
  MixedScene m;
  LightSettings settings;
  settings.sky.kind = SkySettings::Kind::kConstant;
  settings.sky.intensity = 0.3f;
  auto table = build_light_table(m.b.s, m.b.soup(), settings, Bounds3{});
  ASSERT_TRUE(table.is_ok()) << table.status().to_string();
  const size_t lights = table->lights.size();
  ASSERT_EQ(lights, 7u);

  // lux_sample_cdf alone, with zero-width cells that must never come out.
  std::vector<float> cdf = {0, 0, 0.25f, 0.25f, 0.25f, 0.75f, 1, 1};
  Rng rng(5);
  std::vector<float> u(200000);
  for (auto& v : u) v = rng.uniform();
  u.push_back(0.0f);
  u.push_back(0.25f);
  u.push_back(1.0f);  // clamped below 1
  std::vector<int> index;
  std::vector<float> pmf;
  ASSERT_TRUE(test::probe_sample_cdf(cdf, u, &index, &pmf).is_ok());
  std::vector<double> observed(7), expected(7);
  for (size_t i = 0; i < u.size(); ++i) {
    ASSERT_GE(index[i], 0);
    ASSERT_LT(index[i], 7);
    const size_t k = static_cast<size_t>(index[i]);
    ASSERT_GT(pmf[i], 0.0f) << "zero-width cell " << k << " returned for u = " << u[i];
    ASSERT_EQ(pmf[i], cdf[k + 1] - cdf[k]);
    ASSERT_TRUE(cdf[k] <= u[i] && (u[i] < cdf[k + 1] || u[i] >= 1.0f)) << u[i];
    observed[k] += 1;
  }
  for (size_t k = 0; k < 7; ++k) expected[k] = (cdf[k + 1] - cdf[k]) * double(u.size());
  auto chi2 = test_support::chi2_test(observed, expected, 1e-4);
  EXPECT_GT(chi2.p_value, 1e-4) << chi2.detail;

  // Through lux_sample_light: the light index follows the alias table, and the
  // returned pdf carries the selection probability.
  const size_t n = 100000;
  auto s = (*test::LightProbe::create(table.value()))->sample_at({0.5f, 1, 0.5f}, randoms(n, 6));
  ASSERT_TRUE(s.is_ok());
  std::vector<double> obs(lights), exp(lights);
  for (size_t i = 0; i < n; ++i) {
    const size_t k = static_cast<size_t>(s->info[i].x);
    ASSERT_LT(k, lights);
    obs[k] += 1;
    if (s->ok(i) && s->is_delta(i)) {
      ASSERT_EQ(s->wi_pdf[i].w, table->select[k].pmf);
    }
  }
  for (size_t k = 0; k < lights; ++k) exp[k] = double(table->select[k].pmf) * n;
  chi2 = test_support::chi2_test(obs, exp, 1e-4);
  EXPECT_GT(chi2.p_value, 1e-4) << chi2.detail;
}

TEST(LightSampling, AbsentLightTypesCompileOut) {
  MixedScene m;
  auto table = build_light_table(m.b.s, m.b.soup(), {}, Bounds3{});
  ASSERT_TRUE(table.is_ok()) << table.status().to_string();
  device::FeatureSet point_only;
  point_only.set(device::Feature::LIGHT_POINT);
  auto probe = test::LightProbe::create(table.value(), point_only);
  ASSERT_TRUE(probe.is_ok()) << probe.status().to_string();
  const size_t n = 2000;
  auto s = (*probe)->sample_at({0, 0, 0}, randoms(n, 7));
  ASSERT_TRUE(s.is_ok());
  size_t points = 0;
  for (size_t i = 0; i < n; ++i) {
    const bool is_point = s->info[i].x == 0;
    EXPECT_EQ(s->ok(i), is_point) << "only the compiled type samples";
    points += is_point;
  }
  EXPECT_GT(points, 0u);
  // No light feature at all still compiles (a scene lit only by nothing).
  auto none = test::LightProbe::create(table.value(), device::FeatureSet());
  ASSERT_TRUE(none.is_ok()) << none.status().to_string();
  auto s2 = (*none)->sample_at({0, 0, 0}, randoms(16, 8));
  ASSERT_TRUE(s2.is_ok());
  for (size_t i = 0; i < 16; ++i) EXPECT_FALSE(s2->ok(i));
}

}  // namespace
}  // namespace luxel::pipeline
