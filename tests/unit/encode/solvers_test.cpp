// Accuracy of the host reference solvers (core thesis §7.2-7.3) on synthetic
// bases: agreement between solvers, optimality, non-negativity.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "test_bases.h"

namespace luxel::encode {
namespace {

using namespace testing;

double signal_rms(const Signal& f, bool hemisphere = false) {
  return function_rms_difference(
      f, [](const Vec3&) { return 0.0; }, hemisphere);
}

// For an orthonormal basis G = I, so naive projection is least squares
// (§7.2): identical with the exact Gram, and within Monte Carlo error of the
// discrete least squares (estimated G -> I as N grows).
TEST(EncodeSolvers, NaiveProjectionIsLeastSquaresForOrthonormalBasis) {
  const Basis exact = sh2_basis(/*with_identity_gram=*/true);
  const Basis estimated = sh2_basis(false);
  Signal f{&exact, random_non_negative_weights(9, 7, 0.0), {0.3, -0.5, 0.812404}, 1.0};
  const std::vector<Sample> samples = sample_signal(random_directions(16384, 11), f);

  const Result<Solution> naive = solve_naive_projection(exact, samples);
  const Result<Solution> ls_exact = solve_least_squares(exact, samples);
  const Result<Solution> ls_estimated = solve_least_squares(estimated, samples);
  ASSERT_TRUE(naive.is_ok() && ls_exact.is_ok() && ls_estimated.is_ok());
  for (int i = 0; i < 9; ++i)
    EXPECT_NEAR(naive->coefficients[i], ls_exact->coefficients[i], 1e-12) << i;
  EXPECT_EQ(ls_exact->regularization, 0.0);

  // Both are consistent estimators of the continuous projection: with 16384
  // random samples they differ by Monte Carlo error in the estimated G
  // (measured 2.3% of the signal RMS).
  const double difference =
      function_rms_difference(reconstruction(exact, naive->coefficients),
                              reconstruction(exact, ls_estimated->coefficients));
  EXPECT_LT(difference / signal_rms(f), 0.06);
  // The discrete solve minimises the sample residual.
  EXPECT_LE(ls_estimated->residual_rms, naive->residual_rms * (1.0 + 1e-12));

  // With a quadrature-quality point set (Fibonacci spiral) the estimated G is
  // the identity to a few 1e-4, so the two agree closely.
  const std::vector<Sample> spiral = sample_signal(fibonacci_directions(16384), f);
  const Result<Solution> naive_spiral = solve_naive_projection(exact, spiral);
  const Result<Solution> ls_spiral = solve_least_squares(estimated, spiral);
  ASSERT_TRUE(naive_spiral.is_ok() && ls_spiral.is_ok());
  const double spiral_difference =
      function_rms_difference(reconstruction(exact, naive_spiral->coefficients),
                              reconstruction(exact, ls_spiral->coefficients));
  std::printf("  SH L2 naive vs LS: random %.5f, Fibonacci %.5f of signal RMS\n",
              difference / signal_rms(f), spiral_difference / signal_rms(f));
  EXPECT_LT(spiral_difference / signal_rms(f), 2e-3);
}

struct ConvergenceCase {
  const char* name;
  Basis basis;
  bool hemisphere;
  double tolerance;  // relative function-space RMS difference, progressive vs LS
};

// Listing 7.1 converges to the least-squares solution (§7.3.1); measured at
// 65536 uniform random samples against the discrete full solve on the same
// samples, as the function-space RMS of the difference over the signal RMS.
TEST(EncodeSolvers, ProgressiveConvergesToFullLeastSquares) {
  const ConvergenceCase cases[] = {
      {"sg12_lambda8_sphere", sg_basis(12, 8.0), false, 0.03},
      {"sg9_lambda8_hemisphere", sg_basis(9, 8.0, Domain::kHemisphere), true, 0.03},
      {"sh2_sphere", sh2_basis(false), false, 0.03},
  };
  for (const ConvergenceCase& c : cases) {
    Signal f{
        &c.basis, random_non_negative_weights(c.basis.count, 3, 0.3), {0.3, -0.5, 0.812404}, 1.0};
    const std::vector<Sample> samples = sample_signal(random_directions(65536, 5, c.hemisphere), f);
    const Result<Solution> ls = solve_least_squares(c.basis, samples);
    const Result<Solution> progressive = solve_progressive(c.basis, samples);
    const Result<Solution> jacobi = solve_progressive(c.basis, samples, {3.0f, false, false});
    ASSERT_TRUE(ls.is_ok() && progressive.is_ok() && jacobi.is_ok()) << c.name;
    const double scale = signal_rms(f, c.hemisphere);
    const double gs_error =
        function_rms_difference(reconstruction(c.basis, ls->coefficients),
                                reconstruction(c.basis, progressive->coefficients), c.hemisphere) /
        scale;
    const double jacobi_error =
        function_rms_difference(reconstruction(c.basis, ls->coefficients),
                                reconstruction(c.basis, jacobi->coefficients), c.hemisphere) /
        scale;
    std::printf(
        "  %-24s progressive(GS) vs LS %.4f, progressive(Jacobi) vs LS %.4f, residual LS %.4f GS "
        "%.4f\n",
        c.name, gs_error, jacobi_error, ls->relative_residual, progressive->relative_residual);
    EXPECT_LT(gs_error, c.tolerance) << c.name;
    EXPECT_LT(jacobi_error, c.tolerance) << c.name;
    // LS minimises the sample residual; the progressive one is close to it.
    EXPECT_LE(ls->residual_rms, progressive->residual_rms * (1.0 + 1e-9)) << c.name;
    EXPECT_LT(progressive->residual_rms, ls->residual_rms * 1.05 + 1e-6) << c.name;
  }
}

// A signal with an exact non-negative representation: the full NNLS recovers
// it, the progressive NNLS approaches it, and neither goes negative.
TEST(EncodeSolvers, NnlsRecoversNonNegativeExactSolution) {
  const Basis basis = sg_basis(12, 8.0);
  Signal f{&basis, random_non_negative_weights(12, 21, 0.4), {0.3, -0.5, 0.812404}, 0.0};
  const std::vector<Sample> samples = sample_signal(random_directions(32768, 9), f);
  const Result<Solution> nnls = solve_nnls(basis, samples);
  const Result<Solution> progressive = solve_progressive(basis, samples, {3.0f, true, true});
  ASSERT_TRUE(nnls.is_ok() && progressive.is_ok());
  for (int i = 0; i < 12; ++i) {
    EXPECT_NEAR(nnls->coefficients[i], f.weights[i], 1e-8) << "lobe " << i;
    EXPECT_GE(progressive->coefficients[i], 0.0) << "lobe " << i;
  }
  EXPECT_LT(nnls->relative_residual, 1e-9);
  const double error = function_rms_difference(reconstruction(basis, nnls->coefficients),
                                               reconstruction(basis, progressive->coefficients)) /
                       signal_rms(f);
  std::printf("  progressive NNLS vs NNLS (exact signal): %.4f of signal RMS\n", error);
  EXPECT_LT(error, 0.03);
}

// With the non-representable lobe the unconstrained solution goes negative;
// NNLS stays non-negative and is optimal among non-negative coefficient
// vectors: with the sample-estimated Gram its objective is the sample
// residual, so no other non-negative vector may have a smaller one.
TEST(EncodeSolvers, NnlsIsNonNegativeAndOptimal) {
  const Basis basis = sg_basis(12, 8.0);
  Signal f{&basis, random_non_negative_weights(12, 4, 0.5), {0.3, -0.5, 0.812404}, 4.0};
  for (int n : {32, 128, 2048}) {
    const std::vector<Sample> samples = sample_signal(random_directions(n, 100 + n), f);
    const Result<Solution> ls = solve_least_squares(basis, samples);
    const Result<Solution> nnls = solve_nnls(basis, samples);
    const Result<Solution> progressive = solve_progressive(basis, samples, {3.0f, true, true});
    ASSERT_TRUE(ls.is_ok() && nnls.is_ok() && progressive.is_ok()) << n;
    Solution clamped = ls.value();
    for (double& v : clamped.coefficients) v = std::max(v, 0.0);
    double clamped_sum = 0.0;
    for (const Sample& s : samples) {
      const double r = s.value - reconstruct(basis, clamped.coefficients, s.direction);
      clamped_sum += r * r;
    }
    const double clamped_rms = std::sqrt(clamped_sum / n);
    for (int i = 0; i < 12; ++i) {
      EXPECT_GE(nnls->coefficients[i], 0.0) << n << " lobe " << i;
      EXPECT_GE(progressive->coefficients[i], 0.0) << n << " lobe " << i;
    }
    EXPECT_LE(ls->residual_rms, nnls->residual_rms * (1.0 + 1e-9)) << n;
    EXPECT_LE(nnls->residual_rms, clamped_rms * (1.0 + 1e-9)) << n;
    EXPECT_LE(nnls->residual_rms, progressive->residual_rms * (1.0 + 1e-9)) << n;
    std::printf(
        "  N=%5d residual: LS %.4f NNLS %.4f progressive NNLS %.4f clamped LS %.4f (min LS coef "
        "%.3f)\n",
        n, ls->residual_rms, nnls->residual_rms, progressive->residual_rms, clamped_rms,
        *std::min_element(ls->coefficients.begin(), ls->coefficients.end()));
  }
  // At large N the progressive NNLS is close to the full NNLS (§7.3.3, Fig. 7.7).
  const std::vector<Sample> samples = sample_signal(random_directions(65536, 77), f);
  const Result<Solution> nnls = solve_nnls(basis, samples);
  const Result<Solution> progressive = solve_progressive(basis, samples, {3.0f, true, true});
  ASSERT_TRUE(nnls.is_ok() && progressive.is_ok());
  const double error = function_rms_difference(reconstruction(basis, nnls->coefficients),
                                               reconstruction(basis, progressive->coefficients)) /
                       signal_rms(f);
  std::printf("  N=65536 progressive NNLS vs NNLS: %.4f of signal RMS\n", error);
  EXPECT_LT(error, 0.05);
}

TEST(EncodeSolvers, RejectsBadInput) {
  const Basis basis = sg_basis(6, 4.0);
  std::vector<Sample> samples = {{{0, 0, 1}, 1.0}, {{1, 0, 0}, NAN}};
  const Result<Solution> bad_value = solve_least_squares(basis, samples);
  ASSERT_FALSE(bad_value.is_ok());
  EXPECT_NE(bad_value.status().message().find("sample 1"), std::string::npos)
      << bad_value.status().message();
  EXPECT_FALSE(solve_naive_projection(basis, std::span<const Sample>()).is_ok());
  Basis wrong_gram = basis;
  wrong_gram.gram = std::vector<double>(5, 0.0);
  samples[1].value = 0.5;
  EXPECT_FALSE(solve_nnls(wrong_gram, samples).is_ok());
  EXPECT_FALSE(solve_progressive(basis, samples, {0.0f, false, true}).is_ok());
}

}  // namespace
}  // namespace luxel::encode
