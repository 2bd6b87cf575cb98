#include "reference/agreement_stats.h"

#include <cmath>

namespace luxel::reference {
namespace {

// Continued fraction of the incomplete beta function (modified Lentz),
// Numerical Recipes 3rd ed. §6.4 (betacf).
double beta_continued_fraction(double a, double b, double x) {
  constexpr int kMaxIterations = 500;
  constexpr double kEps = 1e-15, kTiny = 1e-300;
  const double qab = a + b, qap = a + 1, qam = a - 1;
  double c = 1, d = 1 - qab * x / qap;
  if (std::abs(d) < kTiny) d = kTiny;
  d = 1 / d;
  double h = d;
  for (int m = 1; m <= kMaxIterations; ++m) {
    const double m2 = 2.0 * m;
    double aa = m * (b - m) * x / ((qam + m2) * (a + m2));
    d = 1 + aa * d;
    if (std::abs(d) < kTiny) d = kTiny;
    c = 1 + aa / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1 / d;
    h *= d * c;
    aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
    d = 1 + aa * d;
    if (std::abs(d) < kTiny) d = kTiny;
    c = 1 + aa / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1 / d;
    const double step = d * c;
    h *= step;
    if (std::abs(step - 1) < kEps) break;
  }
  return h;
}

// Regularised incomplete beta I_x(a, b).
double incomplete_beta(double a, double b, double x) {
  if (x <= 0) return 0;
  if (x >= 1) return 1;
  const double front = std::exp(std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) +
                                a * std::log(x) + b * std::log1p(-x));
  if (x < (a + 1) / (a + b + 2)) return front * beta_continued_fraction(a, b, x) / a;
  return 1 - front * beta_continued_fraction(b, a, 1 - x) / b;
}

}  // namespace

double two_sided_p(double t, double dof) {
  t = std::abs(t);
  if (std::isinf(t)) return 0;
  if (!(dof < 1e7)) return std::erfc(t / std::sqrt(2.0));
  // P(|T| > t) = I_{dof / (dof + t^2)}(dof / 2, 1 / 2).
  return incomplete_beta(0.5 * dof, 0.5, dof / (dof + t * t));
}

double two_sided_critical(double alpha, double dof) {
  double lo = 0, hi = 1;
  while (two_sided_p(hi, dof) > alpha && hi < 1e12) hi *= 2;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (two_sided_p(mid, dof) > alpha ? lo : hi) = mid;
  }
  return hi;
}

double sidak_alpha(double family_alpha, size_t tests) {
  if (tests == 0) return family_alpha;
  // 1 - (1 - alpha)^(1/m) without cancellation for tiny alpha.
  return -std::expm1(std::log1p(-family_alpha) / static_cast<double>(tests));
}

Comparison compare(const Estimate& a, const Estimate& b) {
  Comparison c;
  const double va = a.std_error * a.std_error, vb = b.std_error * b.std_error;
  const double var = va + vb;
  if (!(var > 0)) {
    // Both exact (e.g. a texel no light reaches): equal or infinitely apart.
    c.t = a.mean == b.mean ? 0.0 : std::copysign(INFINITY, a.mean - b.mean);
    c.p_value = a.mean == b.mean ? 1.0 : 0.0;
    return c;
  }
  c.t = (a.mean - b.mean) / std::sqrt(var);
  const double denominator = va * va / a.dof + vb * vb / b.dof;  // 0 for known variances
  c.dof = denominator > 0 ? var * var / denominator : kKnownVariance;
  c.p_value = two_sided_p(c.t, c.dof);
  return c;
}

}  // namespace luxel::reference
