// Piecewise-constant distributions as normalised CDFs, built on the host and
// sampled on the device by kernels/shading/distribution.h.
#pragma once

#include <cstddef>
#include <vector>

#include "kernels/shared/light.h"

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

// The alias table of `weights` (Walker 1977, built with Vose's method, IEEE
// TSE 17(9), 1991, in double precision): n entries for n weights, sampled in
// O(1) by kernels/shading/distribution.h (lux_sample_alias). Each entry's pmf
// is the probability the float table actually realises (realised_pmf), not
// the ideal weight ratio, so a sample's pmf and the pmf MIS evaluates are the
// one the sampler follows. Weights must be finite, >= 0, and not all zero.
std::vector<cl::LuxAliasEntry> build_alias_table(const std::vector<double>& weights);

// Probability with which a uniform u in [0, 1) selects each index of
// `table` (the cell's own share below its threshold plus the shares it
// receives as an alias), in double.
std::vector<double> realised_pmf(const std::vector<cl::LuxAliasEntry>& table);

}  // namespace luxel::pipeline
