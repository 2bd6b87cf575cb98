// Warps of kernels/sampling/warp.h on the device: chi-square goodness of fit
// against their densities, and the orthonormal basis.
#include <cmath>
#include <random>

#include "fixture.h"

namespace luxel::sampling_test {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr size_t kSamples = size_t(1) << 19;

std::vector<Vec3> directions_of(const std::vector<float4>& points) {
  std::vector<Vec3> dirs;
  dirs.reserve(points.size());
  for (const float4& p : points) dirs.push_back(to_vec3(p));
  return dirs;
}

std::vector<float4> node_directions(const std::vector<DirectionBinning::Node>& nodes) {
  std::vector<float4> dirs;
  dirs.reserve(nodes.size());
  for (const auto& n : nodes) dirs.push_back(to_float4(n.dir));
  return dirs;
}

using WarpTest = SamplingTest;

TEST_F(WarpTest, CosineHemisphereMatchesItsDensity) {
  ASSIGN_OR_FAIL(points, probe().warp(Warp::kCosineHemisphere, 0.0f, kSamples));
  const auto binning = SphericalBinning::uniform(32, 64, 0.0, 1.0);
  const auto nodes = binning.quadrature();
  ASSIGN_OR_FAIL(pdf_f, probe().cosine_hemisphere_pdf(node_directions(nodes)));
  const std::vector<double> pdf(pdf_f.begin(), pdf_f.end());
  const auto chi2 =
      directional_chi2(binning, nodes, pdf, directions_of(points), kSamples, kFamilySignificance);
  EXPECT_TRUE(chi2.passed) << chi2.detail;
  // The density reported with each sample is cos(theta) / pi of that sample.
  for (size_t i = 0; i < 4096; ++i)
    ASSERT_NEAR(points[i].w, std::max(0.0f, points[i].z) / kPi, 1e-6) << "sample " << i;
}

TEST_F(WarpTest, UniformHemisphereAndSphereAreUniform) {
  const double significance = kFamilySignificance / 2;
  {
    ASSIGN_OR_FAIL(points, probe().warp(Warp::kUniformHemisphere, 0.0f, kSamples));
    EXPECT_NEAR(points[0].w, 1.0 / (2.0 * kPi), 1e-7) << "lux_uniform_hemisphere_pdf";
    const auto binning = SphericalBinning::uniform(32, 64, 0.0, 1.0);
    const auto nodes = binning.quadrature();
    const std::vector<double> pdf(nodes.size(), 1.0 / (2.0 * kPi));
    const auto chi2 =
        directional_chi2(binning, nodes, pdf, directions_of(points), kSamples, significance);
    EXPECT_TRUE(chi2.passed) << "hemisphere: " << chi2.detail;
  }
  {
    ASSIGN_OR_FAIL(points, probe().warp(Warp::kUniformSphere, 0.0f, kSamples));
    const auto binning = SphericalBinning::uniform(32, 64, -1.0, 1.0);
    const auto nodes = binning.quadrature();
    const std::vector<double> pdf(nodes.size(), 1.0 / (4.0 * kPi));
    const auto chi2 =
        directional_chi2(binning, nodes, pdf, directions_of(points), kSamples, significance);
    EXPECT_TRUE(chi2.passed) << "sphere: " << chi2.detail;
  }
}

TEST_F(WarpTest, UniformConeMatchesItsDensityForWideAndNarrowCones) {
  // From a sun-sized cone to one wider than a hemisphere.
  const float cos_maxes[] = {0.99999f, 0.9f, 0.3f, -0.6f};
  const double significance = kFamilySignificance / std::size(cos_maxes);
  for (float cos_max : cos_maxes) {
    ASSIGN_OR_FAIL(points, probe().warp(Warp::kUniformCone, cos_max, kSamples));
    EXPECT_NEAR(points[0].w, 1.0 / (2.0 * kPi * (1.0 - double(cos_max))), 1e-3 * points[0].w)
        << cos_max;
    // The binned range is the cone itself, so every node sees the device's
    // lux_uniform_cone_pdf (reported with each sample).
    const auto binning = SphericalBinning::uniform(32, 64, double(cos_max), 1.0);
    const auto nodes = binning.quadrature();
    const std::vector<double> pdf(nodes.size(), double(points[0].w));
    const auto chi2 =
        directional_chi2(binning, nodes, pdf, directions_of(points), kSamples, significance);
    EXPECT_TRUE(chi2.passed) << "cos_max " << cos_max << ": " << chi2.detail;
  }
}

TEST_F(WarpTest, UniformTriangleIsAreaUniform) {
  ASSIGN_OR_FAIL(points, probe().warp(Warp::kUniformTriangle, 0.0f, kSamples));
  // Square cells of the (b1, b2) plane; the triangle b1 + b2 <= 1 covers
  // whole cells below the diagonal and half of each diagonal cell.
  const int res = 32;
  std::vector<double> observed(size_t(res * res) + 1, 0.0), expected(size_t(res * res) + 1, 0.0);
  for (int i = 0; i < res; ++i)
    for (int j = 0; j < res; ++j) {
      const double area = (i + j + 2 <= res) ? 1.0 : (i + j + 1 == res ? 0.5 : 0.0);
      expected[size_t(i * res + j)] = double(kSamples) * 2.0 * area / (res * res);
    }
  for (const float4& p : points) {
    const double b1 = p.x, b2 = p.y;
    if (b1 < 0.0 || b2 < 0.0 || b1 + b2 > 1.0 + 1e-6) {
      observed[size_t(res * res)] += 1.0;  // outside the triangle; expects 0
      continue;
    }
    const int i = std::min(int(b1 * res), res - 1), j = std::min(int(b2 * res), res - 1);
    observed[size_t(i * res + j)] += 1.0;
  }
  const auto chi2 = chi2_test(observed, expected, kFamilySignificance);
  EXPECT_TRUE(chi2.passed) << chi2.detail;
}

TEST_F(WarpTest, OnbIsOrthonormalRightHandedAndRoundTrips) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<float4> normals, vectors;
  // The poles and the neighbourhood of -z, where simpler bases break down.
  for (Vec3 n : {Vec3{0, 0, 1}, Vec3{0, 0, -1}, Vec3{1, 0, 0}, Vec3{0, -1, 0}, Vec3{1e-7, 0, -1},
                 Vec3{0, 1e-4, -1}, Vec3{-3e-4, 2e-4, -1}, Vec3{1, 1, 1e-9}})
    normals.push_back(to_float4(normalize(n)));
  while (normals.size() < 4096)
    normals.push_back(to_float4(spherical_direction(2 * u(rng) - 1, 2 * kPi * u(rng))));
  for (size_t i = 0; i < normals.size(); ++i)
    vectors.push_back(to_float4(spherical_direction(2 * u(rng) - 1, 2 * kPi * u(rng))));
  ASSIGN_OR_FAIL(out, probe().onb(normals, vectors));
  const double tol = 2e-6;
  for (size_t i = 0; i < normals.size(); ++i) {
    const Vec3 n = to_vec3(normals[i]), t = to_vec3(out[4 * i]), b = to_vec3(out[4 * i + 1]);
    const Vec3 world = to_vec3(out[4 * i + 2]), back = to_vec3(out[4 * i + 3]),
               v = to_vec3(vectors[i]);
    SCOPED_TRACE(testing::Message()
                 << "normal " << i << " (" << n.x << ", " << n.y << ", " << n.z << ")");
    ASSERT_NEAR(length(t), 1.0, tol);
    ASSERT_NEAR(length(b), 1.0, tol);
    ASSERT_NEAR(dot(t, b), 0.0, tol);
    ASSERT_NEAR(dot(t, n), 0.0, tol);
    ASSERT_NEAR(dot(b, n), 0.0, tol);
    ASSERT_NEAR(dot(cross(t, b), n), 1.0, tol) << "right-handed";
    ASSERT_NEAR(length(world), 1.0, 4 * tol) << "to_world keeps length";
    ASSERT_NEAR(dot(world, n), v.z, 4 * tol) << "local z is the normal";
    ASSERT_NEAR(length(back - v), 0.0, 4 * tol) << "to_local inverts to_world";
  }
}

}  // namespace
}  // namespace luxel::sampling_test
