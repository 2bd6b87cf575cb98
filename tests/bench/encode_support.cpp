#include "encode_support.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace luxel::bench {

// ---- Checks that make the smoke run meaningful.
Checks g_checks;

bool all_finite(const std::vector<double>& v) {
  return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
}

void check_coefficients(const std::vector<double>& b, bool non_negative, const std::string& what) {
  ++g_checks.solutions;
  if (!all_finite(b)) g_checks.fail(what + ": non-finite coefficient");
  if (non_negative && std::any_of(b.begin(), b.end(), [](double x) { return x < 0.0; }))
    g_checks.fail(what + ": negative coefficient from a non-negative solver");
}

// The solution's coefficients, checked; NaNs (and a recorded failure) when
// the solver returned an error.
std::vector<double> checked(const Result<enc::Solution>& r, int n, bool non_negative,
                            const std::string& what) {
  if (!r.is_ok()) {
    g_checks.fail(what + ": " + r.status().to_string());
    return std::vector<double>(size_t(n), NAN);
  }
  check_coefficients(r->coefficients, non_negative, what);
  if (!std::isfinite(r->residual_rms)) g_checks.fail(what + ": non-finite residual");
  return r->coefficients;
}

double check_value(double v, const std::string& what) {
  if (!std::isfinite(v)) g_checks.fail(what + ": non-finite value");
  return v;
}

// ---- Bases.

enc::SphericalBasis make_basis(enc::BasisKind kind, int lobes, float sharpness,
                               enc::BasisDomain layout, enc::BasisDomain fit) {
  enc::BasisSpec spec;
  spec.kind = kind;
  spec.lobe_count = lobes;
  spec.sharpness = sharpness;
  spec.lobe_layout = layout;
  spec.fit_domain = fit;
  Result<enc::SphericalBasis> b = enc::SphericalBasis::create(spec);
  if (!b.is_ok()) {
    std::fprintf(stderr, "bench_encode: %s\n", b.status().to_string().c_str());
    std::exit(1);
  }
  return b.value();
}

enc::SphericalBasis sg_basis(int lobes, float sharpness, bool hemisphere) {
  const enc::BasisDomain d = hemisphere ? enc::BasisDomain::kHemisphere : enc::BasisDomain::kSphere;
  return make_basis(enc::BasisKind::kSphericalGaussian, lobes, sharpness, d, d);
}

// The engine's basis as the solvers' abstract basis (solvers.h), optionally
// with the exact Gram matrix.
enc::Basis solver_basis(const enc::SphericalBasis& basis, const std::vector<double>* gram) {
  enc::Basis s;
  s.count = basis.size();
  s.domain = basis.spec().fit_domain == enc::BasisDomain::kSphere ? enc::Domain::kSphere
                                                                  : enc::Domain::kHemisphere;
  s.evaluate = [basis](const double d[3], double* values) {
    float f[16];
    basis.evaluate(Vec3{float(d[0]), float(d[1]), float(d[2])}, f);
    for (int i = 0; i < basis.size(); ++i) values[i] = f[i];
  };
  if (gram) s.gram = *gram;
  return s;
}

// ---- Ground truth over a domain by the texel quadrature.

Truth make_truth(const enc::SphericalBasis& basis, const EnvQuadrature& q) {
  Truth t;
  t.n = basis.size();
  const size_t n = size_t(t.n);
  t.gram.assign(n * n, 0.0);
  t.moments.assign(n, 0.0);
  t.area = q.area;
  std::vector<float> b(n);
  for (size_t k = 0; k < q.directions.size(); ++k) {
    basis.evaluate(q.directions[k], b.data());
    const double w = q.weights[k], f = q.values[k];
    t.f2 += w * f * f;
    for (size_t i = 0; i < n; ++i) {
      const double wb = w * b[i];
      t.moments[i] += wb * f;
      for (size_t j = 0; j <= i; ++j) t.gram[i * n + j] += wb * b[j];
    }
  }
  for (size_t i = 0; i < n; ++i)
    for (size_t j = 0; j < i; ++j) t.gram[j * n + i] = t.gram[i * n + j];
  return t;
}

// Exact moments integral f B_i over the quadrature (the signal's support).
std::vector<double> exact_moments(const enc::SphericalBasis& basis, const EnvQuadrature& q) {
  std::vector<double> m(size_t(basis.size()), 0.0);
  std::vector<float> b(size_t(basis.size()));
  for (size_t k = 0; k < q.directions.size(); ++k) {
    basis.evaluate(q.directions[k], b.data());
    const double wf = q.weights[k] * q.values[k];
    for (size_t i = 0; i < m.size(); ++i) m[i] += wf * b[i];
  }
  return m;
}

// Best least-squares fit: G^-1 m with the exact Gram matrix (Eq. 7.3).
std::vector<double> exact_least_squares(const std::vector<double>& gram,
                                        const std::vector<double>& moments,
                                        const std::string& what) {
  Result<std::vector<double>> x = enc::solve_spd(gram, moments);
  if (!x.is_ok()) {
    g_checks.fail(what + ": " + x.status().to_string());
    return std::vector<double>(moments.size(), NAN);
  }
  check_coefficients(x.value(), false, what);
  return x.value();
}

// Best NNLS fit: the library's Lawson-Hanson solver fed the quadrature points
// as samples with values f_k w_k N / area, so that its Monte Carlo moments
// (area / N) sum value_k B_i equal the exact ones, and the exact Gram matrix.
std::vector<double> exact_nnls(const enc::SphericalBasis& basis, const std::vector<double>& gram,
                               const EnvQuadrature& q, const std::string& what) {
  const enc::Basis sb = solver_basis(basis, &gram);
  const double scale = double(q.directions.size()) / enc::domain_area(sb.domain);
  std::vector<enc::Sample> samples;
  samples.reserve(q.directions.size());
  for (size_t k = 0; k < q.directions.size(); ++k) {
    const Vec3 d = q.directions[k];
    samples.push_back({{d.x, d.y, d.z}, q.values[k] * q.weights[k] * scale});
  }
  return checked(enc::solve_nnls(sb, samples), basis.size(), true, what);
}

// Condition number of a symmetric positive definite matrix (cyclic Jacobi
// eigenvalues; n <= 16 here).
double condition_number(std::vector<double> a, int n) {
  for (int sweep = 0; sweep < 100; ++sweep) {
    double off = 0.0;
    for (int p = 0; p < n; ++p)
      for (int r = p + 1; r < n; ++r) off += a[size_t(p * n + r)] * a[size_t(p * n + r)];
    if (off < 1e-30) break;
    for (int p = 0; p < n; ++p) {
      for (int r = p + 1; r < n; ++r) {
        const double apr = a[size_t(p * n + r)];
        if (std::abs(apr) < 1e-300) continue;
        const double theta = (a[size_t(r * n + r)] - a[size_t(p * n + p)]) / (2.0 * apr);
        const double t =
            (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1.0));
        const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
        for (int k = 0; k < n; ++k) {  // columns p, r
          const double akp = a[size_t(k * n + p)], akr = a[size_t(k * n + r)];
          a[size_t(k * n + p)] = c * akp - s * akr;
          a[size_t(k * n + r)] = s * akp + c * akr;
        }
        for (int k = 0; k < n; ++k) {  // rows p, r
          const double apk = a[size_t(p * n + k)], ark = a[size_t(r * n + k)];
          a[size_t(p * n + k)] = c * apk - s * ark;
          a[size_t(r * n + k)] = s * apk + c * ark;
        }
      }
    }
  }
  double lo = INFINITY, hi = 0.0;
  for (int i = 0; i < n; ++i) {
    lo = std::min(lo, std::abs(a[size_t(i * n + i)]));
    hi = std::max(hi, std::abs(a[size_t(i * n + i)]));
  }
  return hi / lo;
}

std::vector<enc::Sample> sample_map(const EnvMap& map, const std::vector<Vec3>& dirs) {
  std::vector<enc::Sample> s;
  s.reserve(dirs.size());
  for (const Vec3& d : dirs) s.push_back({{d.x, d.y, d.z}, double(map.luminance(d))});
  return s;
}

std::string fmt(double v) {
  if (!std::isfinite(v)) return "nan";
  const double a = std::abs(v);
  if (a != 0.0 && (a >= 1e5 || a < 1e-3)) return strprintf("%.3g", v);
  if (a >= 100) return strprintf("%.1f", v);
  if (a >= 10) return strprintf("%.2f", v);
  return strprintf("%.4f", v);
}
std::string pct(double v) {
  return std::isfinite(v) ? strprintf("%.2f", 100.0 * v) : "nan";
}

}  // namespace luxel::bench
