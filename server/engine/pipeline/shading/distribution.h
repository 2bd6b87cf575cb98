// Piecewise-constant distributions as normalised CDFs, built on the host and
// sampled on the device by kernels/shading/distribution.h.
#pragma once

#include <cstddef>
#include <vector>

namespace luxel::pipeline {

// Appends the n + 1 CDF values of `weights` (n = count) to `out`: out[0] = 0,
// non-decreasing, out[n] = 1 exactly. Prefix sums are accumulated in double
// so a million small cells do not drift. Weights must be finite and >= 0.
// All-zero weights give a uniform CDF (a zero row of the sky distribution
// stays indexable; the marginal never selects it). Returns the sum.
double append_cdf(const double* weights, size_t count, std::vector<float>* out);

inline double append_cdf(const std::vector<double>& weights, std::vector<float>* out) {
  return append_cdf(weights.data(), weights.size(), out);
}

}  // namespace luxel::pipeline
