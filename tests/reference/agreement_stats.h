// Statistics for comparing two Monte Carlo estimates of the same quantity
// (after Mitsuba 3's render tests: per-pixel z-tests with a Šidák-corrected
// threshold over the family of all pixels).
//
// An Estimate is a mean with its standard error and the degrees of freedom
// of that error (n - 1 for a sample variance from n independent values;
// infinity when it is effectively known). Two estimates are compared with
// Welch's t statistic, whose degrees of freedom follow Welch-Satterthwaite;
// with two large samples it is the usual z-test.
#pragma once

#include <cstddef>
#include <limits>

namespace luxel::reference {

constexpr double kKnownVariance = std::numeric_limits<double>::infinity();

struct Estimate {
  double mean = 0;
  double std_error = 0;
  double dof = kKnownVariance;
};

struct Comparison {
  double t = 0;                 // (a - b) / sqrt(se_a^2 + se_b^2); 0 when both are exact and equal
  double dof = kKnownVariance;  // Welch-Satterthwaite
  double p_value = 1;           // two-sided
};

Comparison compare(const Estimate& a, const Estimate& b);

// Per-test level that keeps the family-wise error at `family_alpha` over
// `tests` independent tests: 1 - (1 - alpha)^(1/m) (Šidák).
double sidak_alpha(double family_alpha, size_t tests);

// Two-sided p-value of t under Student's t with `dof` degrees of freedom
// (the standard normal for dof = infinity).
double two_sided_p(double t, double dof);

// |t| whose two-sided p-value is `alpha` (the critical value of the test).
double two_sided_critical(double alpha, double dof);

}  // namespace luxel::reference
