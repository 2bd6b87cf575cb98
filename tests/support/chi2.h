// Pearson's chi-square goodness-of-fit test for sampling routines (after
// Mitsuba 3's chi2.py), shared by every test folder that checks a sampler
// against its density (tests/unit/kernels/sampling, tests/unit/pipeline/shading).
//
// observed[i] and expected[i] are the sample counts of cell i of a partition
// of the sampled domain; expected sums to the number of samples (a caller
// that bins only part of the domain adds one cell for the rest). Cells
// expected to hold fewer than 5 samples are pooled, sparsest first, until a
// pool expects 5; a remainder joins the first regular cell. A cell the
// density says is (almost) unreachable but that holds many samples fails the
// test outright, whatever the statistic.
#pragma once

#include <string>
#include <vector>

namespace luxel::test_support {

struct Chi2Outcome {
  bool passed = false;  // dof > 0 and p_value >= the significance
  double statistic = 0, p_value = 0;
  int dof = 0;
  std::string detail;  // statistic, p-value and the worst cells, for failure messages
};

Chi2Outcome chi2_test(const std::vector<double>& observed, const std::vector<double>& expected,
                      double significance);

// Upper tail P(X >= x) of the chi-square distribution with dof degrees of freedom.
double chi2_upper_tail(double x, double dof);

// Regularised upper incomplete gamma function Q(a, x).
double gamma_q(double a, double x);

// Per-test significance so that `tests` independent tests together reject a
// correct sampler with probability `alpha` (Sidak correction).
double sidak_alpha(double alpha, int tests);

}  // namespace luxel::test_support
