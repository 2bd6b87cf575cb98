// Basis definitions: Gram matrices (thesis Eq. 7.3, 8.1) and the Ambient Dice
// cosine-lobe partition of unity (§8.3, §8.3.1).
#include "kernels/shared/bases.h"

#include <gtest/gtest.h>

#include <cmath>

#include "encode/basis.h"
#include "encode/gram.h"

namespace luxel::encode {
namespace {

SphericalBasis make(BasisKind kind, int count = 0, float lambda = 3.4f,
                    BasisDomain fit = BasisDomain::kSphere) {
  BasisSpec s;
  s.kind = kind;
  s.lobe_count = count;
  s.sharpness = lambda;
  s.fit_domain = fit;
  Result<SphericalBasis> b = SphericalBasis::create(s);
  EXPECT_TRUE(b.is_ok()) << b.status().to_string();
  return b.value();
}

double max_abs_diff(const GramMatrix& a, const GramMatrix& b) {
  double m = 0.0;
  for (size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(a[i] - b[i]));
  return m;
}

TEST(EncodeBases, ShNumericGramIsIdentity) {
  for (BasisKind kind : {BasisKind::kShL1, BasisKind::kShL2}) {
    const SphericalBasis sh = make(kind);
    // Gauss-Legendre with 16 nodes in z integrates degree-4 products exactly;
    // what remains is float rounding of the SH constants (~1e-7).
    const GramMatrix numeric = gram_numeric(sh, 16);
    const GramMatrix identity = gram_analytic(sh).value();
    EXPECT_LT(max_abs_diff(numeric, identity), 1e-6) << sh.describe().name;
  }
}

TEST(EncodeBases, ShGramOverHemisphereHasNoClosedForm) {
  EXPECT_FALSE(gram_analytic(make(BasisKind::kShL2, 0, 0, BasisDomain::kHemisphere)).is_ok());
  EXPECT_FALSE(gram_analytic(make(BasisKind::kAmbientDice, 12)).is_ok());
}

TEST(EncodeBases, SgAnalyticGramMatchesQuadrature) {
  // Small lambda = wide, heavily overlapping lobes (near-singular G).
  for (int count : {6, 9, 12}) {
    for (float lambda : {0.25f, 1.0f, 3.4f, 8.0f, 24.0f}) {
      const SphericalBasis sg = make(BasisKind::kSphericalGaussian, count, lambda);
      const GramMatrix analytic = gram_analytic(sg).value();
      const GramMatrix numeric = gram_numeric(sg, 96);
      const double diag = analytic[0];  // = integral of B^2 = pi/lambda (1 - e^{-4 lambda})
      // 1e-6: the float lobe axes are unit only to ~6e-8, scaled by 2 lambda.
      EXPECT_NEAR(diag, M_PI / lambda * (1.0 - std::exp(-4.0 * lambda)), 1e-6 * diag);
      EXPECT_LT(max_abs_diff(analytic, numeric), 2e-6 * diag)
          << "sg" << count << " lambda " << lambda;
    }
  }
}

TEST(EncodeBases, SgHemisphereGramIsSymmetricPositive) {
  BasisSpec s{BasisKind::kSphericalGaussian, 9, 3.4f, BasisDomain::kHemisphere,
              BasisDomain::kHemisphere};
  const SphericalBasis sg = SphericalBasis::create(s).value();
  for (const Vec3& d : sg.directions()) EXPECT_GE(d.z, 0.0f);
  const GramMatrix g = gram(sg);  // numeric: no closed form over the hemisphere
  const GramMatrix finer = gram_numeric(sg, 192);
  EXPECT_LT(max_abs_diff(g, finer), 1e-6 * g[0]);
  // Cholesky succeeding == positive definite.
  EXPECT_TRUE(solve_spd(g, std::vector<double>(9, 1.0)).is_ok());
}

// Sum of lobes at many directions covering the sphere.
double worst_partition_error(const std::vector<Vec3>& vertices, float (*lobe)(float)) {
  double worst = 0.0;
  for (const Vec3& s : spherical_fibonacci(4001, BasisDomain::kSphere)) {
    double sum = 0.0;
    for (const Vec3& v : vertices) sum += lobe(dot(v, s));
    worst = std::max(worst, std::abs(sum - 1.0));
  }
  return worst;
}

float half_x2(float x) {
  return x > 0 ? 0.5f * x * x : 0.0f;
}
float five_sixth_x4(float x) {
  return x > 0 ? 5.0f / 6.0f * x * x * x * x : 0.0f;
}

TEST(EncodeBases, AmbientDiceIcosahedronIsPartitionOfUnity) {
  // §8.3: "at every point on the sphere the unscaled basis functions' values
  // add up to one", and each component x^2/2, 5x^4/6 does so on its own.
  const std::vector<Vec3> ico = icosahedron_vertices();
  ASSERT_EQ(ico.size(), 12u);
  EXPECT_LT(worst_partition_error(ico, lux_ad_cosine_lobe), 2e-6);
  EXPECT_LT(worst_partition_error(ico, half_x2), 2e-6);
  EXPECT_LT(worst_partition_error(ico, five_sixth_x4), 2e-6);
}

TEST(EncodeBases, AmbientDiceHemisphereSetIsARotatedIcosahedron) {
  // §8.3.1: the nine vertices are an icosahedron minus the three that the
  // Bézier variant never uses, rotated so their mean points along +z. The
  // table has 4 digits, hence the 1e-3 tolerances.
  const std::vector<Vec3> v = ambient_dice_hemisphere_vertices();
  Vec3 mean{};
  for (const Vec3& a : v) mean = mean + a;
  EXPECT_LT(std::hypot(mean.x, mean.y), 1e-3f * mean.z);
  const float inv_sqrt5 = 1.0f / std::sqrt(5.0f);
  for (size_t i = 0; i < v.size(); ++i)
    for (size_t j = i + 1; j < v.size(); ++j) {
      // Icosahedron vertices are antipodal (|dot| = 1) or 1/sqrt(5) apart.
      const float d = std::abs(dot(v[i], v[j]));
      EXPECT_LT(std::min(std::abs(d - inv_sqrt5), std::abs(d - 1.0f)), 1e-3f) << i << "," << j;
    }

  // Completed with the antipodes of v1..v3 it is a partition of unity again...
  std::vector<Vec3> completed = v;
  for (int i = 0; i < 3; ++i) completed.push_back(v[size_t(i)] * -1.0f);
  EXPECT_LT(worst_partition_error(completed, lux_ad_cosine_lobe), 1e-3);

  // ...so on the hemisphere the nine lobes sum to 1 minus the omitted lobes:
  // not exactly 1 (the thesis calls the omitted contribution negligible; it
  // is zero at the pole and largest at the horizon).
  const SphericalBasis ad9 = make(BasisKind::kAmbientDice, 9);
  double worst_deficit = 0.0;
  for (const Vec3& s : spherical_fibonacci(2001, BasisDomain::kHemisphere)) {
    double sum = 0.0, omitted = 0.0;
    for (float b : ad9.evaluate(s)) sum += b;
    for (int i = 0; i < 3; ++i) omitted += lux_ad_cosine_lobe(-dot(v[size_t(i)], s));
    EXPECT_NEAR(sum + omitted, 1.0, 1e-3);
    EXPECT_LE(sum, 1.0 + 1e-3);
    worst_deficit = std::max(worst_deficit, omitted);
  }
  RecordProperty("ad9_worst_hemisphere_deficit", std::to_string(worst_deficit));
}

TEST(EncodeBases, DescriptionNamesTheBasis) {
  const SphericalBasis sg = SphericalBasis::from_name("sg12", 3.4f).value();
  const std::string json = sg.describe().to_json();
  EXPECT_NE(json.find("\"sg12\""), std::string::npos);
  EXPECT_NE(json.find("sharpness"), std::string::npos);
  EXPECT_EQ(sg.describe().directions.size(), 12u);
  EXPECT_FALSE(SphericalBasis::from_name("sg7").is_ok());
  EXPECT_FALSE(SphericalBasis::from_name("ambient-dice10").is_ok());
  EXPECT_FALSE(SphericalBasis::from_name("wavelet").is_ok());
  EXPECT_EQ(SphericalBasis::from_name("ambient-dice9").value().size(), 9);
}

}  // namespace
}  // namespace luxel::encode
