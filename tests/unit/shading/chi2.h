// Pearson's chi-square goodness-of-fit test for sampling routines (after
// Mitsuba 3's chi2.py): cells whose expected count is below 5 are pooled; a
// sample in a cell the pdf says is unreachable fails outright.
#pragma once

#include <string>
#include <vector>

namespace luxel::pipeline::test {

struct Chi2Result {
  double statistic = 0;
  int dof = 0;
  double p_value = 1;
  std::string message;  // empty, or why the test failed before the statistic
};

// observed[i], expected[i]: counts per cell (expected sums to about the
// number of samples).
Chi2Result chi2_test(const std::vector<double>& observed, const std::vector<double>& expected);

// Upper regularized incomplete gamma Q(a, x).
double gamma_q(double a, double x);

// Per-test significance so that `tests` independent tests together reject a
// correct sampler with probability `alpha` (Sidak correction).
double sidak_alpha(double alpha, int tests);

}  // namespace luxel::pipeline::test
