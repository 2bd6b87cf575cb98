// Progressive sample sequences of kernels/sampling/sequence.h (thesis §6.2)
// on the device: stratification of every power-of-two prefix, determinism,
// decorrelation across seeds and dimensions, and convergence against the
// LUX_SEQUENCE_RANDOM ablation.
#include <bit>
#include <cmath>
#include <random>
#include <set>

#include "fixture.h"

namespace luxel::sampling_test {
namespace {

constexpr uint32_t kOneD = 1, kTwoD = 2;

// Queries for samples [0, count) of one (dimension, seed) sequence.
std::vector<uint4> prefix_queries(uint32_t count, uint32_t dimension, uint32_t seed,
                                  uint32_t arity) {
  std::vector<uint4> q(count);
  for (uint32_t i = 0; i < count; ++i) q[i] = {i, dimension, seed, arity};
  return q;
}

const uint32_t kSeeds[] = {0u, 1u, 2u, 0xdeadbeefu, 0x9e3779b9u, 12345u, 0xffffffffu, 77777u};

using SequenceTest = SamplingTest;

// Each prefix of 2^k points is a (0,k,2)-net: every elementary interval
// [i/2^a, (i+1)/2^a) x [j/2^(k-a), (j+1)/2^(k-a)) holds exactly one point.
TEST_F(SequenceTest, PowerOfTwoPrefixesAreZeroTwoNets) {
  for (uint32_t seed : kSeeds)
    for (uint32_t dimension : {0u, 1u, 7u, 1000u}) {
      ASSIGN_OR_FAIL(points, probe().sequence(Build::kSobolSpecular,
                                              prefix_queries(1024, dimension, seed, kTwoD)));
      for (int k = 4; k <= 10; ++k)
        for (int a = 0; a <= k; ++a) {
          std::vector<int> hits(size_t(1) << k, 0);
          for (size_t i = 0; i < (size_t(1) << k); ++i) {
            const uint32_t cx = uint32_t(points[i].x * float(1u << a));
            const uint32_t cy = uint32_t(points[i].y * float(1u << (k - a)));
            ASSERT_LT(points[i].x, 1.0f);
            ASSERT_LT(points[i].y, 1.0f);
            hits[(size_t(cx) << (k - a)) | cy]++;
          }
          for (size_t c = 0; c < hits.size(); ++c)
            ASSERT_EQ(hits[c], 1) << "seed " << seed << " dimension " << dimension << ": first 2^"
                                  << k << " points, intervals 2^-" << a << " x 2^-" << (k - a)
                                  << ", cell " << c;
        }
    }
}

TEST_F(SequenceTest, OneDimensionalPrefixesAreStratified) {
  for (uint32_t seed : kSeeds)
    for (uint32_t dimension : {0u, 3u, 999u}) {
      ASSIGN_OR_FAIL(points, probe().sequence(Build::kSobolSpecular,
                                              prefix_queries(1024, dimension, seed, kOneD)));
      for (int k = 1; k <= 10; ++k) {
        std::set<uint32_t> cells;
        for (size_t i = 0; i < (size_t(1) << k); ++i)
          cells.insert(uint32_t(points[i].x * float(1u << k)));
        ASSERT_EQ(cells.size(), size_t(1) << k)
            << "seed " << seed << " dimension " << dimension << " k " << k;
      }
    }
}

TEST_F(SequenceTest, IdenticalInputsGiveIdenticalBits) {
  for (Build build : {Build::kSobolSpecular, Build::kRandomDiffuseOnly}) {
    std::vector<uint4> queries;
    std::mt19937 rng(3);
    for (int i = 0; i < 20000; ++i) {
      const uint32_t index = uint32_t(rng() >> 12), dimension = uint32_t(rng() % 64),
                     seed = uint32_t(rng());
      queries.push_back({index, dimension, seed, 1u + uint32_t(rng() & 1u)});
    }
    // The same queries launched again in reverse order land on other
    // work-items and work-groups.
    std::vector<uint4> reversed(queries.rbegin(), queries.rend());
    ASSIGN_OR_FAIL(first, probe().sequence(build, queries));
    ASSIGN_OR_FAIL(second, probe().sequence(build, reversed));
    for (size_t i = 0; i < queries.size(); ++i) {
      const float2 a = first[i], b = second[queries.size() - 1 - i];
      ASSERT_EQ(std::bit_cast<uint32_t>(a.x), std::bit_cast<uint32_t>(b.x)) << "query " << i;
      ASSERT_EQ(std::bit_cast<uint32_t>(a.y), std::bit_cast<uint32_t>(b.y)) << "query " << i;
    }
  }
}

// Fraction of equal x coordinates between two sequences of 256 samples.
double fraction_equal(const std::vector<float2>& a, const std::vector<float2>& b) {
  size_t same = 0;
  for (size_t i = 0; i < a.size(); ++i) same += a[i].x == b[i].x;
  return double(same) / double(a.size());
}

TEST_F(SequenceTest, SeedsAndDimensionsGiveDifferentSequences) {
  auto seq = [&](uint32_t dimension, uint32_t seed, uint32_t arity) {
    return probe().sequence(Build::kSobolSpecular, prefix_queries(256, dimension, seed, arity));
  };
  ASSIGN_OR_FAIL(base, seq(0, 1, kTwoD));
  ASSIGN_OR_FAIL(other_seed, seq(0, 2, kTwoD));
  ASSIGN_OR_FAIL(other_dimension, seq(1, 1, kTwoD));
  ASSIGN_OR_FAIL(one_d, seq(0, 1, kOneD));
  // Equal 24-bit values happen by chance with probability ~2^-24 each.
  EXPECT_LT(fraction_equal(base, other_seed), 0.01);
  EXPECT_LT(fraction_equal(base, other_dimension), 0.01);
  EXPECT_LT(fraction_equal(base, one_d), 0.01) << "1D and 2D dimensions are separate";
}

// Owen scrambling makes every single point uniform over seeds (which keeps
// per-texel estimates unbiased), even for consecutive seeds.
TEST_F(SequenceTest, EachPointIsUniformOverSeeds) {
  const uint32_t indices[] = {0u, 1u, 6u, 1000u};
  const uint32_t dimensions[] = {0u, 5u};
  const double significance =
      kFamilySignificance / (std::size(indices) * std::size(dimensions) * 2);
  const uint32_t seeds = 1u << 16;
  const int res = 16;
  for (uint32_t arity : {kOneD, kTwoD})
    for (uint32_t index : indices)
      for (uint32_t dimension : dimensions) {
        std::vector<uint4> queries(seeds);
        for (uint32_t s = 0; s < seeds; ++s) queries[s] = {index, dimension, s, arity};
        ASSIGN_OR_FAIL(points, probe().sequence(Build::kSobolSpecular, queries));
        const int cells = res * res;
        std::vector<double> observed(size_t(cells), 0.0),
            expected(size_t(cells), double(seeds) / cells);
        for (const float2& p : points) {
          // 1D: 256 intervals; 2D: 16 x 16 cells.
          const int c =
              arity == kTwoD ? int(p.x * res) * res + int(p.y * res) : int(p.x * res * res);
          observed[size_t(c)] += 1.0;
        }
        const auto chi2 = chi2_test(observed, expected, significance);
        EXPECT_TRUE(chi2.passed) << arity << "D index " << index << " dimension " << dimension
                                 << ": " << chi2.detail;
      }
}

// Integral over [0, 1] of exp(-scale (x - c)^2).
double gauss_integral(double c, double scale) {
  const double s = std::sqrt(scale);
  return std::sqrt(3.14159265358979323846) / (2.0 * s) *
         (std::erf(s * (1.0 - c)) + std::erf(s * c));
}

struct ConvergenceCase {
  const char* name;
  uint32_t dimension, arity;
};

// RMS error over seeds of the N-sample estimate of a smooth integral:
// f(x, y) = exp(-4 (x - 0.3)^2) exp(-4 (y - 0.6)^2) in 2D, f(x) = exp(-4 (x - 0.3)^2) in 1D.
double rms_error(Probe& probe, Build build, const ConvergenceCase& c, uint32_t samples,
                 uint32_t seeds, double reference, Status* status) {
  std::vector<uint4> queries;
  for (uint32_t s = 0; s < seeds; ++s)
    for (uint32_t i = 0; i < samples; ++i)
      queries.push_back({i, c.dimension, 0x1000u + s, c.arity});
  auto points = probe.sequence(build, queries);
  if (!points) {
    *status = points.status();
    return 0.0;
  }
  double sum_sq = 0.0;
  for (uint32_t s = 0; s < seeds; ++s) {
    double estimate = 0.0;
    for (uint32_t i = 0; i < samples; ++i) {
      const float2 p = points.value()[size_t(s) * samples + i];
      double f = std::exp(-4.0 * (p.x - 0.3) * (p.x - 0.3));
      if (c.arity == kTwoD) f *= std::exp(-4.0 * (p.y - 0.6) * (p.y - 0.6));
      estimate += f;
    }
    estimate /= samples;
    sum_sq += (estimate - reference) * (estimate - reference);
  }
  return std::sqrt(sum_sq / seeds);
}

// The point of the sequences: at 256 samples per texel the Sobol build's error
// is far below the random ablation's, and the ablation's error is what
// independent uniform samples give (sigma / sqrt(N)). Owen scrambling also
// buys a faster rate for smooth integrands, RMSE ~ N^-1.5 (Owen 1997),
// where an unscrambled or merely shifted net converges like N^-1.
TEST_F(SequenceTest, SobolConvergesFasterThanTheRandomAblation) {
  const uint32_t seeds = 256;
  const ConvergenceCase cases[] = {
      {"2D dimension 0", 0, kTwoD}, {"2D dimension 5", 5, kTwoD}, {"1D dimension 2", 2, kOneD}};
  for (const ConvergenceCase& c : cases) {
    const double ix = gauss_integral(0.3, 4.0), iy = gauss_integral(0.6, 4.0);
    const double ix2 = gauss_integral(0.3, 8.0), iy2 = gauss_integral(0.6, 8.0);
    const double mean = c.arity == kTwoD ? ix * iy : ix;
    const double second = c.arity == kTwoD ? ix2 * iy2 : ix2;
    Status st;
    double sobol[3];
    const uint32_t counts[3] = {64, 256, 1024};
    for (int k = 0; k < 3; ++k) {
      sobol[k] = rms_error(probe(), Build::kSobolSpecular, c, counts[k], seeds, mean, &st);
      ASSERT_TRUE(st.is_ok()) << st.to_string();
    }
    const double random = rms_error(probe(), Build::kRandomDiffuseOnly, c, 256, seeds, mean, &st);
    ASSERT_TRUE(st.is_ok()) << st.to_string();
    const double random_expected = std::sqrt((second - mean * mean) / 256);
    // RMSE over 256 seeds has a relative spread of ~4.5%; +-25% is 5 sigma.
    EXPECT_NEAR(random / random_expected, 1.0, 0.25) << c.name << ": random RMSE " << random;
    EXPECT_LT(sobol[1], 0.2 * random)
        << c.name << ": Sobol RMSE " << sobol[1] << " vs random " << random;
    // 16x the samples: N^-1.5 divides the error by 64, N^-1 by 16.
    EXPECT_GT(sobol[0] / sobol[2], 30.0)
        << c.name << ": RMSE " << sobol[0] << " at 64 samples, " << sobol[2] << " at 1024";
    std::printf(
        "[ sequence ] %s, %u seeds: RMSE Sobol %.3g / %.3g / %.3g at 64 / 256 / 1024 samples; "
        "random %.3g at 256 (sigma/sqrt(N) = %.3g)\n",
        c.name, seeds, sobol[0], sobol[1], sobol[2], random, random_expected);
  }
}

// The ablation must be what it claims: independent uniform numbers. 2^16
// samples of one texel fill 16 x 16 cells uniformly, whether the pair is the
// x and y of one 2D dimension or coordinates of two different dimensions.
TEST_F(SequenceTest, RandomAblationIsUniformAndIndependent) {
  const uint32_t count = 1u << 16, seed = 99u;
  auto fetch = [&](uint32_t dimension, uint32_t arity) {
    return probe().sequence(Build::kRandomDiffuseOnly,
                            prefix_queries(count, dimension, seed, arity));
  };
  ASSIGN_OR_FAIL(d0, fetch(0, kTwoD));
  ASSIGN_OR_FAIL(d1, fetch(1, kTwoD));
  ASSIGN_OR_FAIL(e0, fetch(0, kOneD));
  ASSIGN_OR_FAIL(e1, fetch(1, kOneD));
  struct PairCase {
    const char* name;
    const std::vector<float2>* a;
    bool a_y;
    const std::vector<float2>* b;
    bool b_y;
  };
  const PairCase cases[] = {{"2D dim 0 x, y", &d0, false, &d0, true},
                            {"2D dim 0 x, 2D dim 1 x", &d0, false, &d1, false},
                            {"1D dim 0, 1D dim 1", &e0, false, &e1, false},
                            {"2D dim 1 y, 1D dim 0", &d1, true, &e0, false}};
  const int res = 16;
  for (const PairCase& c : cases) {
    std::vector<double> observed(size_t(res * res), 0.0),
        expected(size_t(res * res), double(count) / (res * res));
    for (uint32_t i = 0; i < count; ++i) {
      const float u = c.a_y ? (*c.a)[i].y : (*c.a)[i].x, v = c.b_y ? (*c.b)[i].y : (*c.b)[i].x;
      observed[size_t(int(u * res) * res + int(v * res))] += 1.0;
    }
    const auto chi2 = chi2_test(observed, expected, kFamilySignificance / std::size(cases));
    EXPECT_TRUE(chi2.passed) << c.name << ": " << chi2.detail;
  }
}

// Within one texel, different dimensions must pair up like independent
// samples (padding, Burley 2020 §4). For f(u, v) = g(u) h(v) with u and v
// from two dimensions, each of u and v alone is integrated almost exactly,
// so the error is the interaction term; independently paired points leave
// it at sqrt(Var g Var h / N). Correlated dimensions (e.g. a shared index
// shuffle) leave an error that does not shrink with N at all.
TEST_F(SequenceTest, PaddedDimensionsPairLikeIndependentSamples) {
  struct Source {
    uint32_t dimension, arity;
    bool y;
  };
  struct PairCase {
    const char* name;
    Source u, v;
  };
  const PairCase cases[] = {{"2D dim 0 x, 2D dim 1 x", {0, kTwoD, false}, {1, kTwoD, false}},
                            {"2D dim 0 y, 2D dim 1 y", {0, kTwoD, true}, {1, kTwoD, true}},
                            {"2D dim 3 y, 2D dim 9 x", {3, kTwoD, true}, {9, kTwoD, false}},
                            {"2D dim 0 x, 1D dim 0", {0, kTwoD, false}, {0, kOneD, false}},
                            {"1D dim 0, 1D dim 1", {0, kOneD, false}, {1, kOneD, false}}};
  const uint32_t samples = 256, seeds = 128;
  const double ig = gauss_integral(0.3, 4.0), ih = gauss_integral(0.6, 4.0);
  const double var_g = gauss_integral(0.3, 8.0) - ig * ig,
               var_h = gauss_integral(0.6, 8.0) - ih * ih;
  const double independent_rmse = std::sqrt(var_g * var_h / samples);
  for (const PairCase& c : cases) {
    auto fetch = [&](const Source& src) {
      std::vector<uint4> queries;
      for (uint32_t s = 0; s < seeds; ++s)
        for (uint32_t i = 0; i < samples; ++i)
          queries.push_back({i, src.dimension, 0x2000u + s, src.arity});
      return probe().sequence(Build::kSobolSpecular, queries);
    };
    ASSIGN_OR_FAIL(us, fetch(c.u));
    ASSIGN_OR_FAIL(vs, fetch(c.v));
    double sum_sq = 0.0;
    for (uint32_t s = 0; s < seeds; ++s) {
      double estimate = 0.0;
      for (uint32_t i = 0; i < samples; ++i) {
        const size_t k = size_t(s) * samples + i;
        const double u = c.u.y ? us[k].y : us[k].x, v = c.v.y ? vs[k].y : vs[k].x;
        estimate += std::exp(-4.0 * (u - 0.3) * (u - 0.3)) * std::exp(-4.0 * (v - 0.6) * (v - 0.6));
      }
      estimate /= samples;
      sum_sq += (estimate - ig * ih) * (estimate - ig * ih);
    }
    const double rmse = std::sqrt(sum_sq / seeds);
    // Owen-shuffled padding measures 1.1-1.2x the independent pairing; the
    // RMSE over 128 seeds scatters by ~6%.
    EXPECT_LT(rmse, 1.5 * independent_rmse)
        << c.name << ": RMSE " << rmse << ", independent pairing " << independent_rmse;
  }
}

// The shift-XOR form of Sobol dimension 1 in sequence.h against the
// definition: XOR of the direction numbers v_{k+1} = v_k ^ (v_k >> 1),
// v_0 = 2^31, over the set bits k of the index.
TEST_F(SequenceTest, SobolDimensionOneMatchesItsDirectionNumbers) {
  auto reference = [](uint32_t index) {
    uint32_t result = 0;
    for (uint32_t v = 0x80000000u; index != 0; index >>= 1, v ^= v >> 1)
      if (index & 1u) result ^= v;
    return result;
  };
  std::vector<uint32_t> in = {0u, 1u, 2u, 3u, 0xFFFFFFFFu, 0x80000000u, 0x7FFFFFFFu};
  for (uint32_t k = 0; k < 32; ++k) in.push_back(1u << k);
  std::mt19937 rng(11);
  while (in.size() < (1u << 16)) in.push_back(static_cast<uint32_t>(rng()));
  auto out = probe().sobol_dim1(in);
  ASSERT_TRUE(out) << out.status().to_string();
  size_t wrong = 0;
  for (size_t i = 0; i < in.size(); ++i)
    if (out.value()[i] != reference(in[i]) && ++wrong < 5)
      ADD_FAILURE() << "index " << in[i] << ": " << out.value()[i] << " != " << reference(in[i]);
  EXPECT_EQ(wrong, 0u);
}

TEST_F(SequenceTest, HashAvalanches) {
  // Flipping any input bit flips each output bit with probability 1/2.
  const size_t n = 1 << 15;
  std::mt19937 rng(11);
  std::vector<uint32_t> in;
  for (size_t i = 0; i < n; ++i) {
    const uint32_t x = rng();
    in.push_back(x);
    for (int bit = 0; bit < 32; ++bit) in.push_back(x ^ (1u << bit));
  }
  ASSIGN_OR_FAIL(out, probe().hash(in));
  std::vector<double> flips(32 * 32, 0.0);
  for (size_t i = 0; i < n; ++i) {
    const uint32_t h = out[i * 33];
    for (int bit = 0; bit < 32; ++bit) {
      const uint32_t diff = h ^ out[i * 33 + 1 + size_t(bit)];
      for (int o = 0; o < 32; ++o) flips[size_t(bit * 32 + o)] += (diff >> o) & 1u;
    }
  }
  // Standard error 0.5 / sqrt(2^15) = 0.0028; 0.03 is over 10 of them.
  for (int bit = 0; bit < 32; ++bit)
    for (int o = 0; o < 32; ++o)
      ASSERT_NEAR(flips[size_t(bit * 32 + o)] / n, 0.5, 0.03)
          << "input bit " << bit << ", output bit " << o;
}

}  // namespace
}  // namespace luxel::sampling_test
