// ProgressiveVariance (bake/progressive_variance.h) on synthetic texel
// states whose true error is known, against the Welford variance:
//  - independent normal samples: both estimates have expectation sigma^2 / n
//    (checked over 20,000 texels; taking the variance of the milestone's
//    mean for that of the final one, the injected error, must fail);
//  - a stratified sequence integrating a step (a texel half in shadow):
//    samples at the van der Corput points with a random shift per texel,
//    so the mean of 2^k samples is within 2^-k of the truth. Welford's
//    variance (independent samples) overstates the squared error by orders
//    of magnitude; the two-point estimate must stay within a small factor.
#include "bake/progressive_variance.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <random>

namespace luxel::pipeline {
namespace {

// Welford state of T texels, fed `per_iteration` samples of each per
// iteration; milestones as the bake takes them.
struct Simulation {
  BakeCheckpoint state;
  ProgressiveVariance pv;
  std::vector<double> mean, m2;

  explicit Simulation(size_t texels) : mean(texels, 0.0), m2(texels, 0.0) {
    state.mean.assign(texels, cl::float4{});
    state.m2.assign(texels, cl::float4{});
    state.weight.assign(texels, cl::float2{});
    state.spp.assign(texels, 0u);
  }
  // sample(texel, k): the texel's k-th sample.
  void run(uint32_t iterations, uint32_t per_iteration,
           const std::function<double(size_t, uint32_t)>& sample) {
    for (uint32_t it = 0; it < iterations; ++it) {
      for (size_t t = 0; t < mean.size(); ++t)
        for (uint32_t j = 0; j < per_iteration; ++j) {
          const uint32_t k = state.spp[t];
          const double x = sample(t, k), d = x - mean[t];
          mean[t] += d / (k + 1);
          m2[t] += d * (x - mean[t]);
          state.spp[t] = k + 1;
          state.mean[t].w = static_cast<float>(mean[t]);
          state.m2[t].w = static_cast<float>(m2[t]);
          state.weight[t] = {float(k + 1), float(k + 1)};
        }
      const double mean_spp = double(state.spp[0]);
      if (it + 1 < iterations && pv.due(mean_spp)) pv.record(state, mean_spp);
    }
  }
};

struct Ratios {
  double two_point = 0, welford = 0, of_y_s = 0;  // mean estimate / mean true squared error
};

Ratios ratios(const Simulation& sim, const std::function<double(size_t)>& truth) {
  double sum_true = 0, sum_two = 0, sum_welford = 0, sum_injected = 0;
  for (size_t t = 0; t < sim.mean.size(); ++t) {
    const double e = double(sim.state.mean[t].w) - truth(t);
    sum_true += e * e;
    bool two_point = false;
    const double v = sim.pv.slot_variance(sim.state, t, &two_point);
    EXPECT_TRUE(two_point) << t;
    sum_two += v;
    sum_welford += welford_variance(sim.state, t);
    // Injected error: the variance of y_s taken for that of y_n, which is
    // more accurate (n / s times the estimate; s = 64, see the callers).
    sum_injected += v * double(sim.state.spp[t]) / 64.0;
  }
  Ratios r{sum_two / sum_true, sum_welford / sum_true, sum_injected / sum_true};
  std::printf(
      "  two-point / true %.3f, Welford / true %.3f, injected (y_s's variance) / true %.3f\n",
      r.two_point, r.welford, r.of_y_s);
  return r;
}

TEST(ProgressiveVariance, MilestonesDoubleFromFour) {
  ProgressiveVariance pv;
  EXPECT_FALSE(pv.due(3.9));
  EXPECT_TRUE(pv.due(4));
  BakeCheckpoint s;
  s.mean.assign(1, cl::float4{});
  s.spp.assign(1, 4u);
  pv.record(s, 4);
  EXPECT_FALSE(pv.due(7.9));
  EXPECT_TRUE(pv.due(8));
  pv.reset();
  EXPECT_TRUE(pv.due(4));
}

TEST(ProgressiveVariance, IndependentSamplesHaveTheVarianceOfTheMean) {
  const size_t texels = 20000;
  Simulation sim(texels);
  std::mt19937_64 rng(17);
  std::normal_distribution<double> noise(0.0, 1.0);
  // 24 iterations of 4: n = 96, milestones at 4 ... 64; s = 64 (as near
  // n / 2 as 32, and the newer wins ties).
  sim.run(24, 4, [&](size_t t, uint32_t) { return 1.0 + 0.001 * double(t % 7) + noise(rng); });
  const Ratios r = ratios(sim, [](size_t t) { return 1.0 + 0.001 * double(t % 7); });
  // 20,000 chi-square(1) terms: the mean is within 1 +- 0.01 (1 sd); the
  // true squared errors are themselves chi-square, hence +- 6 %.
  EXPECT_NEAR(r.two_point, 1.0, 0.06);
  EXPECT_NEAR(r.welford, 1.0, 0.06);
  EXPECT_GT(std::abs(r.of_y_s - 1.0), 0.06) << "the injected error must be detected";
}

// Radical inverse in base 2.
double van_der_corput(uint32_t k) {
  uint32_t b = k;
  b = (b << 16) | (b >> 16);
  b = ((b & 0x00ff00ffu) << 8) | ((b & 0xff00ff00u) >> 8);
  b = ((b & 0x0f0f0f0fu) << 4) | ((b & 0xf0f0f0f0u) >> 4);
  b = ((b & 0x33333333u) << 2) | ((b & 0xccccccccu) >> 2);
  b = ((b & 0x55555555u) << 1) | ((b & 0xaaaaaaaau) >> 1);
  return double(b) * 0x1p-32;
}

TEST(ProgressiveVariance, StratifiedStepIsNotOverstated) {
  const size_t texels = 20000;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<double> edge(texels), shift(texels);
  for (size_t t = 0; t < texels; ++t) {
    edge[t] = uniform(rng);
    shift[t] = uniform(rng);
  }
  Simulation sim(texels);
  sim.run(24, 4, [&](size_t t, uint32_t k) {
    const double u = std::fmod(van_der_corput(k) + shift[t], 1.0);
    return u < edge[t] ? 1.0 : 0.0;
  });
  const Ratios r = ratios(sim, [&](size_t t) { return edge[t]; });
  EXPECT_GT(r.welford, 10.0);  // independent samples' variance: far too large
  EXPECT_GT(r.two_point, 0.5);
  EXPECT_LT(r.two_point, 4.0);
}

TEST(ProgressiveVariance, TexelsWithoutAMilestoneKeepWelford) {
  Simulation sim(3);
  sim.run(1, 16, [](size_t t, uint32_t k) { return double(t + (k % 3)); });
  for (size_t t = 0; t < 3; ++t) {
    bool two_point = true;
    EXPECT_EQ(sim.pv.slot_variance(sim.state, t, &two_point), welford_variance(sim.state, t));
    EXPECT_FALSE(two_point);
  }
}

}  // namespace
}  // namespace luxel::pipeline
