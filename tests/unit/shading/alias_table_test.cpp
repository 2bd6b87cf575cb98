// The light-selection alias table (shading/cdf.h on the
// host, lux_sample_alias in kernels/shading/distribution.h on PoCL):
//  - the table realises the weights exactly (closed form: every u cell is
//    enumerated, no sampling), over sizes and dynamic ranges light tables see;
//  - the device sampler follows the realised pmf (chi-square) and reports the
//    pmf of the index it returns;
//  - a corrupted table must fail the same checks (injected error).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "shading/cdf.h"
#include "shading_probe.h"
#include "support/chi2.h"
#include "test_scenes.h"

namespace luxel::pipeline {
namespace {

using test::Rng;

// Two chi-square tests in this file, 1% family-wise false-failure rate.
const double kAlpha = test_support::sidak_alpha(0.01, 2);

// Largest relative difference between the realised pmf of `table` and
// weights / sum, and whether every entry is well formed and stores its own
// realised pmf. The empty string means the table is right.
std::string check_table(const std::vector<cl::LuxAliasEntry>& table,
                        const std::vector<double>& weights, double tolerance) {
  if (table.size() != weights.size()) return "size";
  double total = 0;
  for (double w : weights) total += w;
  const std::vector<double> realised = realised_pmf(table);
  for (size_t i = 0; i < table.size(); ++i) {
    const cl::LuxAliasEntry& e = table[i];
    if (!(e.threshold >= 0.0f && e.threshold <= 1.0f)) return "threshold " + std::to_string(i);
    if (e.alias >= table.size()) return "alias " + std::to_string(i);
    if (e.pmf != static_cast<float>(realised[i])) return "stored pmf " + std::to_string(i);
    const double want = weights[i] / total;
    const double err = want > 0 ? std::abs(realised[i] / want - 1.0) : realised[i];
    if (!(err <= tolerance))
      return "pmf " + std::to_string(i) + ": " + std::to_string(realised[i]) + " vs " +
             std::to_string(want);
  }
  return "";
}

std::vector<double> random_weights(size_t n, double decades, uint32_t seed) {
  Rng rng(seed);
  std::vector<double> w(n);
  for (auto& v : w) v = std::pow(10.0, decades * double(rng.uniform()));
  return w;
}

TEST(AliasTable, RealisesTheWeightsExactly) {
  // Float thresholds keep 24 bits: the realised pmf is within a few 1e-7 of
  // the ideal one relative to 1/n, so relative to a tiny weight it can be off
  // by (largest / smallest weight) times that. 1e-3 over six decades.
  for (size_t n : {size_t(1), size_t(2), size_t(7), size_t(864), size_t(100000)}) {
    const std::vector<double> w = random_weights(n, 6.0, 11u + uint32_t(n));
    const std::vector<cl::LuxAliasEntry> t = build_alias_table(w);
    EXPECT_EQ(check_table(t, w, 1e-3), "") << "n = " << n;
  }
  // Equal weights: every cell keeps itself; one dominant light among many.
  const std::vector<double> equal(64, 2.5);
  for (const cl::LuxAliasEntry& e : build_alias_table(equal)) EXPECT_EQ(e.threshold, 1.0f);
  EXPECT_EQ(check_table(build_alias_table(equal), equal, 1e-6), "");
  std::vector<double> dominant(1000, 1e-3);
  dominant[517] = 1e6;
  EXPECT_EQ(check_table(build_alias_table(dominant), dominant, 1e-3), "");
  // Zero weights are never realised.
  const std::vector<double> zeros = {0, 3, 0, 1, 0};
  const auto tz = build_alias_table(zeros);
  EXPECT_EQ(check_table(tz, zeros, 1e-6), "");
  EXPECT_EQ(realised_pmf(tz)[0], 0.0);
  EXPECT_EQ(realised_pmf(tz)[4], 0.0);
}

TEST(AliasTable, ACorruptedTableFailsTheCheck) {
  const std::vector<double> w = random_weights(32, 3.0, 5u);
  std::vector<cl::LuxAliasEntry> t = build_alias_table(w);
  ASSERT_EQ(check_table(t, w, 1e-4), "");
  size_t split = 0;  // an entry that gives part of its cell away
  while (split < t.size() && t[split].threshold == 1.0f) ++split;
  ASSERT_LT(split, t.size());
  auto wrong_alias = t;
  wrong_alias[split].alias = (t[split].alias + 1) % uint32_t(t.size());
  EXPECT_NE(check_table(wrong_alias, w, 1e-4), "");
  auto wrong_threshold = t;
  wrong_threshold[split].threshold *= 0.99f;
  EXPECT_NE(check_table(wrong_threshold, w, 1e-4), "");
  auto wrong_pmf = t;
  wrong_pmf[split].pmf *= 1.001f;
  EXPECT_NE(check_table(wrong_pmf, w, 1e-4), "");
}

// Chi-square of device indices against the realised pmf, and the returned pmf
// must be the returned index's stored pmf.
double device_p_value(const std::vector<cl::LuxAliasEntry>& table, size_t draws, uint32_t seed) {
  Rng rng(seed);
  std::vector<float> u(draws);
  for (auto& v : u) v = rng.uniform();
  u.push_back(0.0f);
  u.push_back(1.0f);  // clamped below 1
  std::vector<int> index;
  std::vector<float> pmf;
  EXPECT_TRUE(test::probe_sample_alias(table, u, &index, &pmf).is_ok());
  if (index.size() != u.size()) return 0.0;
  std::vector<double> observed(table.size()), expected(table.size());
  for (size_t i = 0; i < u.size(); ++i) {
    EXPECT_GE(index[i], 0);
    EXPECT_LT(index[i], int(table.size()));
    if (index[i] < 0 || index[i] >= int(table.size())) return 0.0;
    const size_t k = size_t(index[i]);
    EXPECT_GT(pmf[i], 0.0f) << "zero-probability entry " << k << " returned for u = " << u[i];
    EXPECT_EQ(pmf[i], table[k].pmf);
    observed[k] += 1;
  }
  for (size_t k = 0; k < table.size(); ++k) expected[k] = double(table[k].pmf) * double(u.size());
  const auto chi2 = test_support::chi2_test(observed, expected, kAlpha);
  return chi2.p_value;
}

TEST(AliasTable, DeviceSamplerFollowsTheTable) {
  std::vector<double> w = random_weights(200, 2.0, 3u);
  w[10] = 0;
  w[199] = 0;
  const auto table = build_alias_table(w);
  EXPECT_GT(device_p_value(table, 400000, 21u), kAlpha);

  // Injected error: the same draws judged against a table whose thresholds
  // were shifted after the pmfs were stored must be rejected.
  auto skewed = table;
  for (auto& e : skewed)
    if (e.threshold < 1.0f) e.threshold = std::min(1.0f, e.threshold * 1.5f);
  EXPECT_LT(device_p_value(skewed, 400000, 21u), kAlpha);
}

}  // namespace
}  // namespace luxel::pipeline
