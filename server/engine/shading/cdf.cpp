#include "shading/cdf.h"

#include <algorithm>
#include <cmath>

#include "common/status.h"

namespace luxel::pipeline {

double append_cdf(const double* weights, size_t count, std::vector<float>* out) {
  LUXEL_CHECK(count > 0);
  double total = 0;
  for (size_t i = 0; i < count; ++i) {
    LUXEL_CHECK(weights[i] >= 0);
    total += weights[i];
  }
  out->push_back(0.0f);
  double prefix = 0;
  for (size_t i = 0; i < count; ++i) {
    prefix += total > 0 ? weights[i] : 1.0;
    // Rounding to float is monotone, so the CDF stays non-decreasing.
    out->push_back(
        i + 1 == count ? 1.0f : static_cast<float>(prefix / (total > 0 ? total : double(count))));
  }
  return total;
}

std::vector<cl::LuxAliasEntry> build_alias_table(const std::vector<double>& weights) {
  const size_t n = weights.size();
  LUXEL_CHECK(n > 0);
  double total = 0;
  for (double w : weights) {
    LUXEL_CHECK(w >= 0 && std::isfinite(w));
    total += w;
  }
  LUXEL_CHECK(total > 0);
  // Vose: scaled[i] = n p_i; cells below 1 are topped up from cells above 1.
  std::vector<double> scaled(n);
  std::vector<size_t> small, large;
  for (size_t i = 0; i < n; ++i) {
    scaled[i] = weights[i] / total * double(n);
    (scaled[i] < 1.0 ? small : large).push_back(i);
  }
  std::vector<cl::LuxAliasEntry> table(n);
  for (size_t i = 0; i < n; ++i) table[i] = {1.0f, static_cast<uint32_t>(i), 0.0f, 0u};
  while (!small.empty() && !large.empty()) {
    const size_t s = small.back(), l = large.back();
    small.pop_back();
    table[s].threshold = static_cast<float>(scaled[s]);
    table[s].alias = static_cast<uint32_t>(l);
    scaled[l] -= 1.0 - scaled[s];
    if (scaled[l] < 1.0) {
      large.pop_back();
      small.push_back(l);
    }
  }
  // What is left is 1 up to rounding: those cells keep themselves (threshold
  // 1, set above), which Vose's method prescribes for numerical stability.
  const std::vector<double> pmf = realised_pmf(table);
  for (size_t i = 0; i < n; ++i) table[i].pmf = static_cast<float>(pmf[i]);
  return table;
}

std::vector<double> realised_pmf(const std::vector<cl::LuxAliasEntry>& table) {
  const double n = double(table.size());
  std::vector<double> pmf(table.size(), 0.0);
  for (size_t i = 0; i < table.size(); ++i) {
    const double keep = std::clamp(double(table[i].threshold), 0.0, 1.0);
    pmf[i] += keep / n;
    if (table[i].alias < table.size()) pmf[table[i].alias] += (1.0 - keep) / n;
  }
  return pmf;
}

}  // namespace luxel::pipeline
