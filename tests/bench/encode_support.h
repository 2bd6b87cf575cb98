// Support of bench_encode (encode.cpp): the smoke run's checks, the bases,
// the ground truth of a map by its texel quadrature (Eq. 7.3), and printing.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "common/status.h"
#include "encode/basis.h"
#include "encode/gram.h"
#include "encode/solvers.h"
#include "envmaps.h"

namespace luxel::bench {
namespace enc = luxel::encode;

struct Checks {
  long solutions = 0;
  long failures = 0;
  std::vector<std::string> messages;
  void fail(const std::string& m) {
    ++failures;
    if (messages.size() < 20) messages.push_back(m);
  }
};

// The smoke run's record of failed checks.
extern Checks g_checks;

bool all_finite(const std::vector<double>& v);

void check_coefficients(const std::vector<double>& b, bool non_negative, const std::string& what);

// The solution's coefficients, checked; NaNs (and a recorded failure) when
// the solver returned an error.
std::vector<double> checked(const Result<enc::Solution>& r, int n, bool non_negative,
                            const std::string& what);

double check_value(double v, const std::string& what);

enc::SphericalBasis make_basis(enc::BasisKind kind, int lobes, float sharpness,
                               enc::BasisDomain layout, enc::BasisDomain fit);

enc::SphericalBasis sg_basis(int lobes, float sharpness, bool hemisphere);

// The engine's basis as the solvers' abstract basis (solvers.h), optionally
// with the exact Gram matrix.
enc::Basis solver_basis(const enc::SphericalBasis& basis,
                        const std::vector<double>* gram = nullptr);

struct Truth {
  int n = 0;
  std::vector<double> gram;     // quadrature Gram matrix, n x n
  std::vector<double> moments;  // integral f B_i
  double f2 = 0.0;              // integral f^2
  double area = 0.0;

  double quadratic(const std::vector<double>& d) const {
    double s = 0.0;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) s += d[size_t(i)] * gram[size_t(i * n + j)] * d[size_t(j)];
    return s;
  }
  // Function-space RMSE of sum_i b_i B_i against f over the domain.
  double rmse(const std::vector<double>& b) const {
    double bm = 0.0;
    for (int i = 0; i < n; ++i) bm += b[size_t(i)] * moments[size_t(i)];
    return std::sqrt(std::max(0.0, f2 - 2.0 * bm + quadratic(b)) / area);
  }
  // Function-space RMS of the difference of two reconstructions.
  double distance(const std::vector<double>& a, const std::vector<double>& b) const {
    std::vector<double> d(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) d[size_t(i)] = a[size_t(i)] - b[size_t(i)];
    return std::sqrt(std::max(0.0, quadratic(d)) / area);
  }
  double signal_rms() const { return std::sqrt(f2 / area); }
};

Truth make_truth(const enc::SphericalBasis& basis, const EnvQuadrature& q);

// Exact moments integral f B_i over the quadrature (the signal's support).
std::vector<double> exact_moments(const enc::SphericalBasis& basis, const EnvQuadrature& q);

// Best least-squares fit: G^-1 m with the exact Gram matrix (Eq. 7.3).
std::vector<double> exact_least_squares(const std::vector<double>& gram,
                                        const std::vector<double>& moments,
                                        const std::string& what);

// Best NNLS fit: the library's Lawson-Hanson solver fed the quadrature points
// as samples with values f_k w_k N / area, so that its Monte Carlo moments
// (area / N) sum value_k B_i equal the exact ones, and the exact Gram matrix.
std::vector<double> exact_nnls(const enc::SphericalBasis& basis, const std::vector<double>& gram,
                               const EnvQuadrature& q, const std::string& what);

// Condition number of a symmetric positive definite matrix (cyclic Jacobi
// eigenvalues; n <= 16 here).
double condition_number(std::vector<double> a, int n);

// The map's luminance at each direction, as solver samples.
std::vector<enc::Sample> sample_map(const EnvMap& map, const std::vector<Vec3>& dirs);

// A value for the tables (significant digits by magnitude), a percentage.
std::string fmt(double v);
std::string pct(double v);

}  // namespace luxel::bench
