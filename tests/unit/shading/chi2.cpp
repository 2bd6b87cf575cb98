#include "chi2.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "common/status.h"

namespace luxel::pipeline::test {
namespace {

// Series for P(a, x), x < a + 1 (Numerical Recipes 6.2).
double gamma_p_series(double a, double x) {
  double sum = 1.0 / a, term = sum, ap = a;
  for (int n = 0; n < 1000; ++n) {
    ap += 1;
    term *= x / ap;
    sum += term;
    if (std::fabs(term) < std::fabs(sum) * 1e-15) break;
  }
  return sum * std::exp(-x + a * std::log(x) - std::lgamma(a));
}

// Continued fraction for Q(a, x), x >= a + 1 (modified Lentz).
double gamma_q_fraction(double a, double x) {
  const double tiny = 1e-300;
  double b = x + 1 - a, c = 1 / tiny, d = 1 / b, h = d;
  for (int i = 1; i < 1000; ++i) {
    const double an = -i * (i - a);
    b += 2;
    d = an * d + b;
    if (std::fabs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::fabs(c) < tiny) c = tiny;
    d = 1 / d;
    const double del = d * c;
    h *= del;
    if (std::fabs(del - 1) < 1e-15) break;
  }
  return std::exp(-x + a * std::log(x) - std::lgamma(a)) * h;
}

}  // namespace

double gamma_q(double a, double x) {
  if (x <= 0) return 1.0;
  return x < a + 1 ? 1.0 - gamma_p_series(a, x) : gamma_q_fraction(a, x);
}

double sidak_alpha(double alpha, int tests) { return 1.0 - std::pow(1.0 - alpha, 1.0 / tests); }

Chi2Result chi2_test(const std::vector<double>& observed, const std::vector<double>& expected) {
  LUXEL_CHECK(observed.size() == expected.size());
  Chi2Result r;
  const double total = std::accumulate(observed.begin(), observed.end(), 0.0);
  std::vector<size_t> order(observed.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return expected[a] < expected[b]; });

  double pooled_obs = 0, pooled_exp = 0;
  int cells = 0;
  for (size_t i : order) {
    // A cell the pdf gives (almost) nothing but the sampler visits often.
    if (expected[i] < 1e-9 * total && observed[i] > 1e-5 * total + 1) {
      r.message = strprintf("cell %zu: %.0f samples where the pdf expects %.3g", i, observed[i], expected[i]);
      r.p_value = 0;
      return r;
    }
    if (expected[i] < 5 || pooled_exp > 0) {
      pooled_obs += observed[i];
      pooled_exp += expected[i];
      if (pooled_exp >= 5) {
        r.statistic += (pooled_obs - pooled_exp) * (pooled_obs - pooled_exp) / pooled_exp;
        ++cells;
        pooled_obs = pooled_exp = 0;
      }
      continue;
    }
    r.statistic += (observed[i] - expected[i]) * (observed[i] - expected[i]) / expected[i];
    ++cells;
  }
  if (pooled_exp > 0) {  // leftover pool below 5: fold it into the statistic anyway
    r.statistic += (pooled_obs - pooled_exp) * (pooled_obs - pooled_exp) / pooled_exp;
    ++cells;
  }
  r.dof = cells - 1;
  if (r.dof < 1) {
    r.message = "fewer than two cells with enough expected samples";
    r.p_value = 0;
    return r;
  }
  r.p_value = gamma_q(0.5 * r.dof, 0.5 * r.statistic);
  return r;
}

}  // namespace luxel::pipeline::test
