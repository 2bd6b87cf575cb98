#include "support/chi2.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "common/status.h"

namespace luxel::test_support {
namespace {

// Cells expecting fewer samples are pooled: below this the chi-square
// approximation of Pearson's statistic breaks down.
constexpr double kMinExpected = 5.0;

}  // namespace

// Numerical Recipes §6.2: series below a + 1, Lentz's continued fraction above.
double gamma_q(double a, double x) {
  if (x <= 0.0) return 1.0;
  const double log_prefactor = -x + a * std::log(x) - std::lgamma(a);
  if (x < a + 1.0) {
    double term = 1.0 / a, sum = term;
    for (double ap = a + 1.0; std::fabs(term) > std::fabs(sum) * 1e-16; ap += 1.0) {
      term *= x / ap;
      sum += term;
    }
    return std::max(0.0, 1.0 - sum * std::exp(log_prefactor));
  }
  const double tiny = 1e-300;
  double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
  for (int i = 1; i < 1000000; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::fabs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::fabs(c) < tiny) c = tiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::fabs(delta - 1.0) < 1e-15) break;
  }
  return std::exp(log_prefactor) * h;
}

double chi2_upper_tail(double x, double dof) {
  return gamma_q(0.5 * dof, 0.5 * x);
}

double sidak_alpha(double alpha, int tests) {
  return 1.0 - std::pow(1.0 - alpha, 1.0 / tests);
}

Chi2Outcome chi2_test(const std::vector<double>& observed, const std::vector<double>& expected,
                      double significance) {
  LUXEL_CHECK(observed.size() == expected.size());
  Chi2Outcome out;
  const double total = std::accumulate(observed.begin(), observed.end(), 0.0);
  // Samples piling up where the density is (nearly) zero: a sampler bug the
  // pooling below would only dilute.
  for (size_t i = 0; i < observed.size(); ++i) {
    if (expected[i] < 1e-9 * total && observed[i] > 1e-5 * total + 1) {
      out.detail = strprintf("cell %zu: %.0f samples where the density expects %.3g", i,
                             observed[i], expected[i]);
      return out;
    }
  }
  // Pool the sparsest cells (ascending expectation) until each pool expects
  // kMinExpected; a remainder joins the first regular cell. Cells expecting
  // nothing are pooled too: quadrature may miss a sliver of support at the
  // edge of a cell, while many samples where the density is 0 still blow up
  // the statistic of their pool.
  std::vector<size_t> order(observed.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return expected[a] < expected[b]; });
  struct Cell {
    double obs, exp;
    size_t first;
  };
  std::vector<Cell> cells;
  Cell pool{0, 0, 0};
  bool pooling = false;
  for (size_t i : order) {
    if (!pooling) pool = {0, 0, i};
    pool.obs += observed[i];
    pool.exp += expected[i];
    pooling = pool.exp < kMinExpected;
    if (!pooling) cells.push_back(pool);
  }
  if (pooling) {
    if (cells.empty())
      cells.push_back(pool);
    else
      cells.front().obs += pool.obs, cells.front().exp += pool.exp;
  }
  for (const Cell& c : cells)
    if (c.exp > 0) out.statistic += (c.obs - c.exp) * (c.obs - c.exp) / c.exp;
  out.dof = int(cells.size()) - 1;
  out.p_value = out.dof > 0 ? chi2_upper_tail(out.statistic, out.dof) : 0.0;
  out.passed = out.dof > 0 && out.p_value >= significance;
  // The cells contributing most, for the failure message.
  auto contribution = [](const Cell& c) {
    return c.exp > 0 ? (c.obs - c.exp) * (c.obs - c.exp) / c.exp : 0.0;
  };
  std::sort(cells.begin(), cells.end(),
            [&](const Cell& a, const Cell& b) { return contribution(a) > contribution(b); });
  out.detail = strprintf(
      "chi2 = %.1f, dof = %d, p = %.3g (threshold %.3g); worst cells (first index: observed / "
      "expected):",
      out.statistic, out.dof, out.p_value, significance);
  if (out.dof < 1) out.detail += " fewer than two cells with enough expected samples;";
  for (size_t i = 0; i < std::min<size_t>(cells.size(), 4); ++i)
    out.detail += strprintf(" #%zu: %.0f / %.1f", cells[i].first, cells[i].obs, cells[i].exp);
  return out;
}

}  // namespace luxel::test_support
