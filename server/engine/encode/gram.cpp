#include "encode/gram.h"

#include <cmath>

namespace luxel::encode {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Gauss-Legendre nodes/weights on [-1, 1] by Newton on P_n (Numerical
// Recipes' gauleg): double precision to ~1e-15 for n up to a few hundred.
void gauss_legendre(int n, std::vector<double>& x, std::vector<double>& w) {
  x.assign(size_t(n), 0.0);
  w.assign(size_t(n), 0.0);
  for (int i = 0; i < (n + 1) / 2; ++i) {
    double z = std::cos(kPi * (i + 0.75) / (n + 0.5));
    double dp = 0.0;
    for (int iter = 0; iter < 100; ++iter) {
      double p0 = 1.0, p1 = 0.0;
      for (int k = 1; k <= n; ++k) {
        const double p2 = p1;
        p1 = p0;
        p0 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p2) / k;
      }
      dp = n * (z * p0 - p1) / (z * z - 1.0);
      const double dz = p0 / dp;
      z -= dz;
      if (std::abs(dz) < 1e-15) break;
    }
    x[size_t(i)] = -z;
    x[size_t(n - 1 - i)] = z;
    w[size_t(i)] = w[size_t(n - 1 - i)] = 2.0 / ((1.0 - z * z) * dp * dp);
  }
}

bool has_closed_form(const SphericalBasis& b) {
  return b.spec().fit_domain == BasisDomain::kSphere && b.spec().kind != BasisKind::kAmbientDice;
}

}  // namespace

SphereQuadrature SphereQuadrature::build(BasisDomain domain, int n_z) {
  std::vector<double> x, w;
  gauss_legendre(n_z, x, w);
  const int n_phi = 2 * n_z;
  // Map [-1, 1] to [z0, 1]; dz = half-length * dx.
  const double z0 = domain == BasisDomain::kSphere ? -1.0 : 0.0;
  const double half = 0.5 * (1.0 - z0);
  SphereQuadrature q;
  for (int i = 0; i < n_z; ++i) {
    const double z = z0 + half * (x[size_t(i)] + 1.0);
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    for (int j = 0; j < n_phi; ++j) {
      const double phi = 2.0 * kPi * (j + 0.5) / n_phi;
      q.directions.push_back({float(r * std::cos(phi)), float(r * std::sin(phi)), float(z)});
      q.weights.push_back(half * w[size_t(i)] * 2.0 * kPi / n_phi);
    }
  }
  return q;
}

Result<GramMatrix> gram_analytic(const SphericalBasis& basis) {
  if (!has_closed_form(basis))
    return invalid_argument(strprintf(
        "no closed-form Gram matrix for basis '%s' over the %s", basis.describe().name.c_str(),
        basis.spec().fit_domain == BasisDomain::kSphere ? "sphere" : "hemisphere"));
  const int n = basis.size();
  GramMatrix g(size_t(n * n), 0.0);
  if (basis.spec().kind != BasisKind::kSphericalGaussian) {
    for (int i = 0; i < n; ++i) g[size_t(i * n + i)] = 1.0;  // Eq. 8.1
    return g;
  }
  const double l = basis.spec().sharpness;
  const auto& p = basis.directions();
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const Vec3 a = p[size_t(i)], b = p[size_t(j)];
      const double rx = l * (double(a.x) + b.x), ry = l * (double(a.y) + b.y),
                   rz = l * (double(a.z) + b.z);
      const double r = std::sqrt(rx * rx + ry * ry + rz * rz);
      // 4 pi e^{-2l} sinh(r) / r, written to avoid overflow for large l and
      // the 0/0 at r -> 0 (antipodal lobes): sinh(r)/r -> 1.
      g[size_t(i * n + j)] = r < 1e-8
                                 ? 4.0 * kPi * std::exp(-2.0 * l)
                                 : 2.0 * kPi / r * (std::exp(r - 2.0 * l) - std::exp(-r - 2.0 * l));
    }
  }
  return g;
}

GramMatrix gram_numeric(const SphericalBasis& basis, int n_z) {
  const SphereQuadrature q = SphereQuadrature::build(basis.spec().fit_domain, n_z);
  const int n = basis.size();
  GramMatrix g(size_t(n * n), 0.0);
  std::vector<float> b(static_cast<size_t>(n));
  for (size_t k = 0; k < q.directions.size(); ++k) {
    basis.evaluate(q.directions[k], b.data());
    for (int i = 0; i < n; ++i)
      for (int j = 0; j <= i; ++j)
        g[size_t(i * n + j)] += q.weights[k] * double(b[size_t(i)]) * b[size_t(j)];
  }
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < i; ++j) g[size_t(j * n + i)] = g[size_t(i * n + j)];
  return g;
}

GramMatrix gram(const SphericalBasis& basis) {
  if (has_closed_form(basis)) return gram_analytic(basis).value();
  return gram_numeric(basis);
}

std::vector<double> project(const SphericalBasis& basis, const std::function<double(Vec3)>& f,
                            int n_z) {
  const SphereQuadrature q = SphereQuadrature::build(basis.spec().fit_domain, n_z);
  std::vector<double> m(size_t(basis.size()), 0.0);
  std::vector<float> b(static_cast<size_t>(basis.size()));
  for (size_t k = 0; k < q.directions.size(); ++k) {
    basis.evaluate(q.directions[k], b.data());
    const double fw = f(q.directions[k]) * q.weights[k];
    for (size_t i = 0; i < m.size(); ++i) m[i] += fw * b[i];
  }
  return m;
}

Result<std::vector<double>> solve_spd(const GramMatrix& g, std::vector<double> rhs) {
  const size_t n = rhs.size();
  if (g.size() != n * n)
    return invalid_argument(
        strprintf("Gram matrix has %zu entries, expected %zu", g.size(), n * n));
  std::vector<double> l(n * n, 0.0);
  for (size_t j = 0; j < n; ++j) {
    double d = g[j * n + j];
    for (size_t k = 0; k < j; ++k) d -= l[j * n + k] * l[j * n + k];
    if (!(d > 0.0))
      return invalid_argument(strprintf("Gram matrix is not positive definite at row %zu", j));
    l[j * n + j] = std::sqrt(d);
    for (size_t i = j + 1; i < n; ++i) {
      double s = g[i * n + j];
      for (size_t k = 0; k < j; ++k) s -= l[i * n + k] * l[j * n + k];
      l[i * n + j] = s / l[j * n + j];
    }
  }
  for (size_t i = 0; i < n; ++i) {  // L y = rhs
    for (size_t k = 0; k < i; ++k) rhs[i] -= l[i * n + k] * rhs[k];
    rhs[i] /= l[i * n + i];
  }
  for (size_t i = n; i-- > 0;) {  // L^T x = y
    for (size_t k = i + 1; k < n; ++k) rhs[i] -= l[k * n + i] * rhs[k];
    rhs[i] /= l[i * n + i];
  }
  return rhs;
}

Result<std::vector<float>> fit_least_squares(const SphericalBasis& basis,
                                             const std::function<double(Vec3)>& f, int n_z) {
  Result<std::vector<double>> x = solve_spd(gram(basis), project(basis, f, n_z));
  if (!x) return x.status();
  return std::vector<float>(x.value().begin(), x.value().end());
}

}  // namespace luxel::encode
