// Host reference solvers for spherical basis encodings (core thesis §7.2-7.3).
#include "encode/solvers.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace luxel::encode {
namespace {

Status validate(const Basis& basis, std::span<const Sample> samples) {
  if (basis.count <= 0)
    return invalid_argument(strprintf("basis: lobe count %d is not positive", basis.count));
  if (!basis.evaluate) return invalid_argument("basis: no evaluation function");
  if (basis.gram && basis.gram->size() != size_t(basis.count) * size_t(basis.count)) {
    return invalid_argument(strprintf("basis: Gram matrix has %zu entries, expected %d x %d",
                                      basis.gram->size(), basis.count, basis.count));
  }
  if (samples.empty()) return invalid_argument("samples: none given");
  for (size_t k = 0; k < samples.size(); ++k) {
    const Sample& s = samples[k];
    if (!std::isfinite(s.value))
      return invalid_argument(strprintf("sample %zu: value is not finite", k));
    if (!std::isfinite(s.direction[0]) || !std::isfinite(s.direction[1]) ||
        !std::isfinite(s.direction[2])) {
      return invalid_argument(strprintf("sample %zu: direction is not finite", k));
    }
  }
  return Status::ok();
}

// In-place Cholesky of the n x n row-major SPD matrix a (lower triangle).
// Fails when a pivot is not clearly positive relative to the largest diagonal.
bool cholesky(std::vector<double>& a, int n) {
  double max_diag = 0.0;
  for (int i = 0; i < n; ++i) max_diag = std::max(max_diag, a[i * n + i]);
  const double min_pivot = 1e-14 * max_diag;
  for (int j = 0; j < n; ++j) {
    double d = a[j * n + j];
    for (int k = 0; k < j; ++k) d -= a[j * n + k] * a[j * n + k];
    if (!(d > min_pivot)) return false;
    const double l = std::sqrt(d);
    a[j * n + j] = l;
    for (int i = j + 1; i < n; ++i) {
      double v = a[i * n + j];
      for (int k = 0; k < j; ++k) v -= a[i * n + k] * a[j * n + k];
      a[i * n + j] = v / l;
    }
  }
  return true;
}

void cholesky_solve(const std::vector<double>& l, int n, std::vector<double>& x) {
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < i; ++k) x[i] -= l[i * n + k] * x[k];
    x[i] /= l[i * n + i];
  }
  for (int i = n - 1; i >= 0; --i) {
    for (int k = i + 1; k < n; ++k) x[i] -= l[k * n + i] * x[k];
    x[i] /= l[i * n + i];
  }
}

// Solves (G + ridge I) x = rhs, growing the ridge from `initial` (relative to
// mean diag G) until the factorisation succeeds. Returns the ridge used.
Result<double> regularized_solve(std::vector<double> g, int n, double relative_ridge,
                                 std::vector<double>& x) {
  double mean_diag = 0.0;
  for (int i = 0; i < n; ++i) mean_diag += g[i * n + i] / n;
  if (!(mean_diag > 0.0) || !std::isfinite(mean_diag)) {
    return invalid_argument(
        "Gram matrix: diagonal is zero or not finite (basis vanishes on every sample?)");
  }
  double relative = relative_ridge;
  for (int attempt = 0; attempt < 20; ++attempt) {
    std::vector<double> a = g;
    const double ridge = relative * mean_diag;
    for (int i = 0; i < n; ++i) a[i * n + i] += ridge;
    if (cholesky(a, n)) {
      cholesky_solve(a, n, x);
      return ridge;
    }
    relative = relative > 0.0 ? relative * 10.0 : 1e-12;
  }
  return invalid_argument(
      "Gram matrix: not positive definite even with a ridge of 1e7 x its mean diagonal");
}

void finish_residual(const Basis& basis, std::span<const Sample> samples, Solution& solution) {
  double sum_r2 = 0.0, sum_f2 = 0.0;
  for (const Sample& s : samples) {
    const double r = s.value - reconstruct(basis, solution.coefficients, s.direction);
    sum_r2 += r * r;
    sum_f2 += s.value * s.value;
  }
  solution.residual_rms = std::sqrt(sum_r2 / samples.size());
  solution.relative_residual = sum_f2 > 0.0 ? std::sqrt(sum_r2 / sum_f2) : 0.0;
}

// G: the exact one when the basis carries it, else the sample estimate.
Result<std::vector<double>> gram_for(const Basis& basis, std::span<const Sample> samples) {
  if (basis.gram) return *basis.gram;
  return monte_carlo_gram(basis, samples);
}

}  // namespace

double domain_area(Domain domain) {
  return domain == Domain::kSphere ? 4.0 * std::numbers::pi : 2.0 * std::numbers::pi;
}

double reconstruct(const Basis& basis, std::span<const double> coefficients,
                   const double direction[3]) {
  std::vector<double> values(basis.count);
  basis.evaluate(direction, values.data());
  double sum = 0.0;
  for (int i = 0; i < basis.count; ++i) sum += coefficients[i] * values[i];
  return sum;
}

Result<std::vector<double>> monte_carlo_moments(const Basis& basis,
                                                std::span<const Sample> samples) {
  LUXEL_RETURN_IF_ERROR(validate(basis, samples));
  const int n = basis.count;
  std::vector<double> c(n, 0.0), values(n);
  for (const Sample& s : samples) {
    basis.evaluate(s.direction, values.data());
    for (int i = 0; i < n; ++i) c[i] += s.value * values[i];
  }
  const double scale = domain_area(basis.domain) / samples.size();
  for (double& v : c) v *= scale;
  return c;
}

Result<std::vector<double>> monte_carlo_gram(const Basis& basis, std::span<const Sample> samples) {
  LUXEL_RETURN_IF_ERROR(validate(basis, samples));
  const int n = basis.count;
  std::vector<double> g(size_t(n) * n, 0.0), values(n);
  for (const Sample& s : samples) {
    basis.evaluate(s.direction, values.data());
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j <= i; ++j) g[i * n + j] += values[i] * values[j];
    }
  }
  const double scale = domain_area(basis.domain) / samples.size();
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j <= i; ++j) g[j * n + i] = g[i * n + j] = g[i * n + j] * scale;
  }
  return g;
}

Result<Solution> solve_naive_projection(const Basis& basis, std::span<const Sample> samples) {
  Result<std::vector<double>> moments = monte_carlo_moments(basis, samples);
  if (!moments) return moments.status();
  Solution solution;
  solution.coefficients = std::move(moments).value();
  finish_residual(basis, samples, solution);
  return solution;
}

Result<Solution> solve_least_squares(const Basis& basis, std::span<const Sample> samples,
                                     const FullSolveOptions& options) {
  Result<std::vector<double>> moments = monte_carlo_moments(basis, samples);
  if (!moments) return moments.status();
  Result<std::vector<double>> gram = gram_for(basis, samples);
  if (!gram) return gram.status();
  Solution solution;
  solution.coefficients = std::move(moments).value();
  Result<double> ridge =
      regularized_solve(gram.value(), basis.count, options.relative_ridge, solution.coefficients);
  if (!ridge) return ridge.status();
  solution.regularization = ridge.value();
  finish_residual(basis, samples, solution);
  return solution;
}

// Lawson-Hanson active set on the quadratic form of the normal equations:
// the gradient is w = c - G b; the passive set P holds the free coefficients,
// the others are pinned at zero.
Result<Solution> solve_nnls(const Basis& basis, std::span<const Sample> samples,
                            const FullSolveOptions& options) {
  Result<std::vector<double>> moments = monte_carlo_moments(basis, samples);
  if (!moments) return moments.status();
  Result<std::vector<double>> gram_result = gram_for(basis, samples);
  if (!gram_result) return gram_result.status();
  const std::vector<double>& g = gram_result.value();
  const std::vector<double>& c = moments.value();
  const int n = basis.count;

  double scale = 0.0;  // tolerance on the gradient: relative to the problem size
  for (int i = 0; i < n; ++i) scale = std::max(scale, std::abs(c[i]));
  const double tolerance = 1e-12 * std::max(scale, 1e-300) * n;

  std::vector<double> b(n, 0.0), w(n);
  std::vector<bool> passive(n, false);
  Solution solution;
  auto gradient = [&] {
    for (int i = 0; i < n; ++i) {
      w[i] = c[i];
      for (int j = 0; j < n; ++j) w[i] -= g[i * n + j] * b[j];
    }
  };
  // Least squares restricted to the passive set; zeros elsewhere.
  auto solve_passive = [&](std::vector<double>& z) -> Status {
    std::vector<int> idx;
    for (int i = 0; i < n; ++i)
      if (passive[i]) idx.push_back(i);
    const int m = int(idx.size());
    std::fill(z.begin(), z.end(), 0.0);
    if (m == 0) return Status::ok();  // every coefficient pinned at zero
    std::vector<double> sub(size_t(m) * m), rhs(m);
    for (int a = 0; a < m; ++a) {
      rhs[a] = c[idx[a]];
      for (int bb = 0; bb < m; ++bb) sub[a * m + bb] = g[idx[a] * n + idx[bb]];
    }
    Result<double> ridge = regularized_solve(sub, m, options.relative_ridge, rhs);
    if (!ridge) return ridge.status();
    solution.regularization = std::max(solution.regularization, ridge.value());
    for (int a = 0; a < m; ++a) z[idx[a]] = rhs[a];
    return Status::ok();
  };

  gradient();
  std::vector<double> z(n);
  const int max_iterations = 3 * n + 10;
  for (solution.iterations = 0; solution.iterations < max_iterations; ++solution.iterations) {
    int best = -1;
    for (int i = 0; i < n; ++i) {
      if (!passive[i] && w[i] > tolerance && (best < 0 || w[i] > w[best])) best = i;
    }
    if (best < 0) break;  // KKT conditions hold
    passive[best] = true;
    for (int inner = 0; inner < 3 * n; ++inner) {
      LUXEL_RETURN_IF_ERROR(solve_passive(z));
      bool feasible = true;
      double step = 1.0;
      for (int i = 0; i < n; ++i) {
        if (passive[i] && z[i] <= 0.0) {
          feasible = false;
          step = std::min(step, b[i] / (b[i] - z[i]));
        }
      }
      if (feasible) {
        b = z;
        break;
      }
      // Move towards z until the first passive coefficient hits zero, then
      // pin every coefficient that reached it.
      for (int i = 0; i < n; ++i) {
        if (!passive[i]) continue;
        b[i] += step * (z[i] - b[i]);
        if (b[i] <= 1e-15 * std::max(scale, 1.0)) {
          b[i] = 0.0;
          passive[i] = false;
        }
      }
    }
    gradient();
  }
  for (double& v : b) v = std::max(v, 0.0);
  solution.coefficients = std::move(b);
  finish_residual(basis, samples, solution);
  return solution;
}

ProgressiveEncoder::ProgressiveEncoder(int lobe_count, ProgressiveOptions options)
    : options_(options),
      amplitudes_(size_t(lobe_count), 0.0f),
      integrals_(size_t(lobe_count), 0.0f) {
  LUXEL_CHECK(lobe_count > 0);
}

float ProgressiveEncoder::running_residual_rms() const {
  return std::sqrt(mean_delta_squared_);
}

void ProgressiveEncoder::add_sample(std::span<const float> basis_values, float value,
                                    float weight) {
  LUXEL_CHECK(basis_values.size() == amplitudes_.size());
  LUXEL_CHECK(weight > 0.0f);
  const size_t n = amplitudes_.size();
  total_weight_ += weight;
  // Welford-style running means weigh the new sample by w / W (Eq. 7.11).
  const float sample_weight_scale = weight / total_weight_;

  float delta = value;
  for (size_t i = 0; i < n; ++i) delta -= amplitudes_[i] * basis_values[i];
  mean_delta_squared_ += (delta * delta - mean_delta_squared_) * sample_weight_scale;

  // Eq. 7.15 blends from the naive-projection denominator 1 to the running
  // estimate of mean B_i^2 by 1/W. (Listing 7.1 writes
  // `scale + (1 - scale * I)`, which is not Eq. 7.15; we follow the equation.)
  // With fractional weights 1/W can exceed 1, hence the clamp.
  const float blend = std::min(1.0f / total_weight_, 1.0f);
  for (size_t i = 0; i < n; ++i) {
    const float basis_value = basis_values[i];
    integrals_[i] += (basis_value * basis_value - integrals_[i]) * sample_weight_scale;
    const float spherical_integral = blend + (1.0f - blend) * integrals_[i];
    // Eq. 7.14: b_i += alpha/k * B_i * delta / I_i.
    const float delta_scale =
        options_.acceleration * basis_value * sample_weight_scale / spherical_integral;
    const float previous = amplitudes_[i];
    amplitudes_[i] += delta * delta_scale;
    if (options_.non_negative) amplitudes_[i] = std::max(amplitudes_[i], 0.0f);
    // Gauss-Seidel (§7.3.1): the later lobes see the change just made. With
    // the clamp the change actually applied is used, not the unclamped one.
    if (options_.gauss_seidel) delta -= (amplitudes_[i] - previous) * basis_value;
  }
}

Result<Solution> solve_progressive(const Basis& basis, std::span<const Sample> samples,
                                   const ProgressiveOptions& options) {
  LUXEL_RETURN_IF_ERROR(validate(basis, samples));
  if (!(options.acceleration > 0.0f) || !std::isfinite(options.acceleration)) {
    return invalid_argument(
        strprintf("progressive options: acceleration %g must be positive", options.acceleration));
  }
  const int n = basis.count;
  ProgressiveEncoder encoder(n, options);
  std::vector<double> values(n);
  std::vector<float> values_f(n);
  for (const Sample& s : samples) {
    basis.evaluate(s.direction, values.data());
    for (int i = 0; i < n; ++i) values_f[i] = float(values[i]);
    encoder.add_sample(values_f, float(s.value));
  }
  Solution solution;
  solution.coefficients.assign(encoder.amplitudes().begin(), encoder.amplitudes().end());
  finish_residual(basis, samples, solution);
  return solution;
}

}  // namespace luxel::encode
