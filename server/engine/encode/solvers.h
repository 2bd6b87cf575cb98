// Host reference solvers that encode samples of a spherical signal into a
// linear basis (core thesis, Roughton 2019, Ch. 7.2-7.3).
//
// The basis is abstract (a callable plus a count), so these solvers validate
// any basis the engine defines (SH, spherical Gaussians, Ambient Dice) without
// depending on its code. Signals are scalar: encode colour channel by channel.
//
// Samples are taken uniformly over the basis domain (the whole sphere, or the
// hemisphere z >= 0 of §7.2.1); every Monte Carlo estimate below weighs each
// sample by domain_area / N. Full solves run in double; the progressive
// encoder runs in fp32 as the GPU accumulator will (§7.3.2).
#pragma once

#include <functional>
#include <optional>
#include <span>
#include <vector>

#include "common/status.h"

namespace luxel::encode {

enum class Domain { kSphere, kHemisphere };  // hemisphere: direction z >= 0

// 4*pi for the sphere, 2*pi for the hemisphere.
double domain_area(Domain domain);

// Writes B_0(dir) .. B_{count-1}(dir) into values. dir is a unit vector.
using BasisFunction = std::function<void(const double dir[3], double* values)>;

struct Basis {
  BasisFunction evaluate;
  int count = 0;
  Domain domain = Domain::kSphere;
  // Optional exact Gram matrix G_ij = integral over the domain of B_i B_j
  // (row-major, count*count). When absent, solvers estimate it from the
  // samples, which makes the functional-analysis solve identical to the
  // discrete normal equations A^T A b = A^T f (the area/N factors cancel).
  std::optional<std::vector<double>> gram;
};

struct Sample {
  double direction[3];
  double value;
};

struct Solution {
  std::vector<double> coefficients;
  // sqrt(mean over the samples of (f(s) - sum_i b_i B_i(s))^2).
  double residual_rms = 0.0;
  // residual_rms / sqrt(mean f^2); 0 when the signal is zero.
  double relative_residual = 0.0;
  // Ridge added to the diagonal of G to make it factor (0 when none was needed).
  double regularization = 0.0;
  // NNLS: active-set iterations performed; others: 0.
  int iterations = 0;
};

// Raw moments c_i = integral f B_i, estimated as domain_area/N * sum f B_i.
Result<std::vector<double>> monte_carlo_moments(const Basis& basis,
                                                std::span<const Sample> samples);

// Gram matrix estimated from the sample directions (row-major).
Result<std::vector<double>> monte_carlo_gram(const Basis& basis, std::span<const Sample> samples);

// Naive projection b = c (footnote 2 of §7.2): the least-squares solution only
// when G is the identity, i.e. for orthonormal bases such as SH.
Result<Solution> solve_naive_projection(const Basis& basis, std::span<const Sample> samples);

struct FullSolveOptions {
  // Ridge added to the diagonal relative to mean(diag G) before the first
  // factorisation attempt. 0 gives the exact least-squares solution.
  double relative_ridge = 0.0;
};

// Functional-analysis least squares (Eq. 7.3): solve G b = c by Cholesky.
// When G is numerically singular (wide, heavily overlapping lobes; too few
// samples for the estimated G), a ridge starting at 1e-12 * mean(diag G) is
// added and grown tenfold until G factors; Solution::regularization reports it.
// That biases b towards small norm along the near-null directions of G, which
// barely changes the reconstructed function.
Result<Solution> solve_least_squares(const Basis& basis, std::span<const Sample> samples,
                                     const FullSolveOptions& options = {});

// Non-negative least squares: min b^T G b - 2 c^T b subject to b >= 0, solved
// with the Lawson-Hanson active-set method on (G, c). Coefficients are >= 0.
Result<Solution> solve_nnls(const Basis& basis, std::span<const Sample> samples,
                            const FullSolveOptions& options = {});

struct ProgressiveOptions {
  float acceleration = 3.0f;  // alpha of Eq. 7.14; §7.3 finds 3 quickest
  bool non_negative = false;  // clamp b_i >= 0 after each lobe update (§7.3.1)
  bool gauss_seidel = true;   // update delta after each lobe (§7.3.1); else Jacobi
};

// The progressive least-squares encoder of Listing 7.1, state in fp32: one
// amplitude and one running spherical-integral estimate per lobe plus the
// total sample weight. Memory does not grow with the sample count.
class ProgressiveEncoder {
 public:
  ProgressiveEncoder(int lobe_count, ProgressiveOptions options);

  // basis_values[i] = B_i(direction of the sample); weight > 0.
  void add_sample(std::span<const float> basis_values, float value, float weight = 1.0f);

  std::span<const float> amplitudes() const { return amplitudes_; }
  // Running weighted mean of B_i^2 (the integral of B_i^2 / domain area).
  std::span<const float> spherical_integrals() const { return integrals_; }
  float total_weight() const { return total_weight_; }
  // Running weighted RMS of delta = f - sum b_j B_j measured before each
  // update: a progressive residual that costs nothing extra on the device.
  float running_residual_rms() const;

 private:
  ProgressiveOptions options_;
  std::vector<float> amplitudes_;
  std::vector<float> integrals_;
  float total_weight_ = 0.0f;
  float mean_delta_squared_ = 0.0f;
};

// Feeds the samples in order through a ProgressiveEncoder (unit weights) and
// reports the result in double with the same residual as the full solves.
Result<Solution> solve_progressive(const Basis& basis, std::span<const Sample> samples,
                                   const ProgressiveOptions& options = {});

// sum_i b_i B_i(direction).
double reconstruct(const Basis& basis, std::span<const double> coefficients,
                   const double direction[3]);

}  // namespace luxel::encode
