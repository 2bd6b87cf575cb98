#include "pipeline/shading/distribution.h"

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

}  // namespace luxel::pipeline
