// Adaptive sampling's allocation kernels (kernels/bake/adaptive.h) on the
// real device, from a crafted per-texel state, against the allocation rule
// computed here: every texel gets floor or ceil of its share of the batch,
// the shares follow the texels' relative error times their coverage (with
// the dark floor, the cap and the defensive term), the keys come out sorted
// and sum to the batch, and the result is the same on every run.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "bake/bake_kernels.h"
#include "device/context.h"
#include "kernels/shared/sample_info.h"
#include "support/device_context.h"

namespace luxel {
namespace {

using pipeline::BakeKernel;

// Not a multiple of LUX_ALLOC_GROUP, and more than LUX_ALLOC_GROUP blocks
// (alloc_scan's items then scan several blocks each).
constexpr uint32_t kTexels = 70001;
constexpr uint32_t kBatch = 1u << 20;
constexpr uint32_t kSpp = 16;
constexpr double kUnit = 128, kCap = 32, kMix = 0.2, kDarkFloor = 0.1;

struct TexelState {
  double y = 1;    // mean luminance
  double rel = 0;  // relative standard error of the mean (against y)
  uint32_t spp = kSpp;
  uint32_t valid = LUX_SAMPLES_PER_TEXEL;  // sample positions on geometry (coverage x 64)
};

// Texel t: relative errors 0.5 % .. 10 %; every 50th dark (y = 1e-3 with 50 %
// relative error, i.e. tiny absolute error); texel 7 with 1 sample (counts
// as 100 %); texel 11 with zero variance; every 7th (t % 7 == 1) a chart's
// border texel, a quarter on geometry.
constexpr uint32_t kBorderValid = LUX_SAMPLES_PER_TEXEL / 4;
bool border(uint32_t t) {
  return t % 7 == 1;
}
std::vector<TexelState> crafted_state() {
  std::vector<TexelState> s(kTexels);
  for (uint32_t t = 0; t < kTexels; ++t) {
    s[t].rel = 0.005 * (1 + t % 20);
    if (border(t)) s[t].valid = kBorderValid;
    if (t % 50 == 3) {
      s[t].y = 1e-3;
      s[t].rel = 0.5;
    }
  }
  s[7].spp = 1;
  s[11].rel = 0;
  return s;
}

// An adaptive iteration of kBatch paths over kTexels slots with the given
// dark floor, error scale and defensive term (cap: kCap units).
cl::LuxBakeParams adaptive_params(double floor, double scale, double mix) {
  cl::LuxBakeParams p{};
  p.covered_count = kTexels;
  p.paths = kBatch;
  p.adaptive_pass = 1;
  p.alloc_floor = static_cast<float>(floor);
  p.alloc_scale = static_cast<float>(scale);
  p.alloc_cap = static_cast<float>(kUnit * kCap);
  p.alloc_mix = static_cast<float>(mix);
  return p;
}

class AdaptiveAllocationTest : public testing::DeviceTest<> {
 protected:
  // Runs alloc_weights, alloc_scan, alloc_keys; returns the keys of the
  // batch and the device's weights.
  static void allocate(const std::vector<TexelState>& state, const cl::LuxBakeParams& params,
                       std::vector<uint32_t>& keys, std::vector<uint32_t>& weights) {
    device::Context& ctx = *ctx_;
    device::FeatureSet f;
    f.set(device::Feature::ADAPTIVE);
    auto kernels = pipeline::BakeKernels::create(ctx, f);
    ASSERT_TRUE(kernels) << kernels.status().to_string();
    pipeline::BakeKernelArgs a;
    a.params = params;
    std::vector<cl::float4> mean(kTexels), m2(kTexels);
    std::vector<cl::float2> weight(kTexels);
    std::vector<uint32_t> spp(kTexels);
    for (uint32_t t = 0; t < kTexels; ++t) {
      // Welford state with unit weights: var = m2 / n, se = sqrt(var / n).
      const double n = state[t].spp, se = state[t].rel * state[t].y;
      mean[t].w = static_cast<float>(state[t].y);
      m2[t].w = static_cast<float>(se * se * n * n);
      weight[t] = {static_cast<float>(n), static_cast<float>(n)};
      spp[t] = state[t].spp;
    }
    auto up = [&](auto& buffer, const auto& v, const char* name) {
      auto b = ctx.upload(v, name, CL_MEM_READ_WRITE);
      ASSERT_TRUE(b) << b.status().to_string();
      buffer = std::move(b.value());
    };
    auto placeholder = [&](device::Buffer& b, size_t bytes, const char* name) {
      auto r = ctx.alloc(std::max<size_t>(bytes, 16), name);
      ASSERT_TRUE(r) << r.status().to_string();
      b = std::move(r.value());
    };
    // The scene group: only the sample-info words' valid masks are read
    // (the coverage); slot t's two header words at 2 t.
    std::vector<uint32_t> offsets(kTexels), words(2 * size_t{kTexels});
    for (uint32_t t = 0; t < kTexels; ++t) {
      const uint64_t mask =
          state[t].valid >= 64 ? ~uint64_t{0} : (uint64_t{1} << state[t].valid) - 1;
      offsets[t] = 2 * t;
      words[2 * size_t{t}] = static_cast<uint32_t>(mask);
      words[2 * size_t{t} + 1] = static_cast<uint32_t>(mask >> 32);
    }
    up(a.scene.sample_offsets, offsets, "sample offsets");
    up(a.scene.sample_words, words, "sample words");
    for (device::Buffer* b : {&a.scene.tris, &a.scene.materials, &a.scene.atlas_uvs,
                              &a.scene.instance_first, &a.scene.covered, &a.scene.probes})
      placeholder(*b, 16, "unused");
    up(a.accum.mean, mean, "mean");
    up(a.accum.m2, m2, "m2");
    up(a.accum.weight, weight, "weight");
    up(a.accum.spp, spp, "spp");
    for (device::Buffer* b : {&a.accum.nonfinite, &a.accum.stats, &a.accum.reference,
                              &a.accum.radiance_cache, &a.accum.guide})
      placeholder(*b, 16, "unused");
    placeholder(a.paths.keys, kBatch * 4, "keys");
    for (device::Buffer* b :
         {&a.paths.offsets, &a.paths.paths, &a.paths.rays, &a.paths.hits, &a.paths.shadow_rays,
          &a.paths.shadow_contrib, &a.paths.occluded, &a.paths.alive, &a.paths.tagged})
      placeholder(*b, 16, "unused");
    const size_t blocks = (kTexels + LUX_ALLOC_GROUP - 1) / LUX_ALLOC_GROUP;
    placeholder(a.alloc.alloc_weights, kTexels * 4, "weights");
    placeholder(a.alloc.alloc_blocks, (blocks + 1) * 8, "blocks");
    const size_t grid = blocks * LUX_ALLOC_GROUP;
    for (auto [k, global, local] : {std::tuple{BakeKernel::alloc_weights, grid, size_t{256}},
                                    std::tuple{BakeKernel::alloc_scan, size_t{256}, size_t{256}},
                                    std::tuple{BakeKernel::alloc_keys, grid, size_t{256}}}) {
      ASSERT_TRUE(kernels.value().bind(k, a).is_ok());
      ASSERT_TRUE(ctx.launch(kernels.value()[k], global, local).is_ok());
    }
    keys.assign(kBatch, 0);
    weights.assign(kTexels, 0);
    ASSERT_TRUE(ctx.read(a.paths.keys, keys).is_ok());
    ASSERT_TRUE(ctx.read(a.alloc.alloc_weights, weights).is_ok());
    ASSERT_TRUE(ctx.finish().is_ok());
  }
};

// The allocation rule of kernels/bake/adaptive.h in double precision:
// weight = min(e * scale, cap) * coverage + mix, e = se / max(y, floor) at
// most 1. with_coverage = false: the rule before coverage counted (the
// injected error of CoverageWeighsTheShares).
double expected_weight(const TexelState& s, double floor, double scale, bool with_coverage = true) {
  const double e = s.spp < 2 ? 1.0 : std::min(1.0, s.rel * s.y / std::max(s.y, floor));
  const double coverage = with_coverage ? s.valid / double(LUX_SAMPLES_PER_TEXEL) : 1.0;
  return std::min(e * scale, kUnit * kCap) * coverage + kUnit * kMix;
}

TEST_F(AdaptiveAllocationTest, BatchSplitsByRelativeError) {
  const std::vector<TexelState> state = crafted_state();
  double mean_y = 0, mean_err = 0;
  for (const auto& s : state) {
    mean_y += s.y / kTexels;
    // As the host does: the mean of coverage x relative error.
    mean_err +=
        (s.spp < 2 ? 1.0 : std::min(1.0, s.rel)) * s.valid / LUX_SAMPLES_PER_TEXEL / kTexels;
  }
  const cl::LuxBakeParams p = adaptive_params(kDarkFloor * mean_y, kUnit / mean_err, kUnit * kMix);
  std::vector<uint32_t> keys, weights;
  allocate(state, p, keys, weights);
  if (HasFatalFailure()) return;

  // The weights follow the rule (within the rounding to integers).
  uint64_t total = 0;
  for (uint32_t t = 0; t < kTexels; ++t) {
    const double w = expected_weight(state[t], p.alloc_floor, p.alloc_scale);
    EXPECT_LE(std::fabs(weights[t] - w), 0.5 + 1e-3 * w) << "texel " << t;
    total += weights[t];
  }
  // Sorted keys, all in range: the batch splits exactly.
  ASSERT_TRUE(std::is_sorted(keys.begin(), keys.end()));
  ASSERT_LT(keys.back(), kTexels);
  std::vector<uint32_t> count(kTexels, 0);
  for (uint32_t k : keys) ++count[k];
  // Every texel: floor or ceil of its share of the batch.
  for (uint32_t t = 0; t < kTexels; ++t) {
    const double share = double(kBatch) * weights[t] / double(total);
    EXPECT_GE(count[t], std::floor(share)) << "texel " << t;
    EXPECT_LE(count[t], std::ceil(share)) << "texel " << t;
    EXPECT_GT(count[t], 0u) << "the defensive term samples every texel, texel " << t;
  }
  // More samples where the error is higher: the 10 % texels get about
  // (10 % x scale + mix) / (0.5 % x scale + mix) times the 0.5 % ones'
  // (summed over each class, so floor/ceil rounding averages out).
  double hi = 0, lo = 0;
  for (uint32_t t = 0; t < kTexels; ++t) {
    if (t % 50 == 3 || t == 7 || t == 11 || border(t)) continue;
    if (t % 20 == 19) hi += count[t];
    if (t % 20 == 0) lo += count[t];
  }
  const double ratio = expected_weight(state[19], p.alloc_floor, p.alloc_scale) /
                       expected_weight(state[20], p.alloc_floor, p.alloc_scale);
  EXPECT_GT(ratio, 4.0);
  EXPECT_NEAR(hi / lo, ratio, 0.02 * ratio);
  // The dark texel (50 % relative, y below the floor) counts its error
  // against the floor: about the share of a 0.5 % texel, not of a 50 % one.
  EXPECT_LE(count[3], count[19] / 4);
  // The one-sample texel counts as 100 % error.
  EXPECT_GT(count[7], count[19] * 5);
  // A border texel a quarter on geometry takes (e scale / 4 + mix) /
  // (e scale + mix) of an inner texel's share at the same error (10 %:
  // about 0.29), summed over each class.
  double inner10 = 0, border10 = 0;
  size_t n_inner = 0, n_border = 0;
  for (uint32_t t = 0; t < kTexels; ++t) {
    if (t % 20 != 19 || t % 50 == 3) continue;
    (border(t) ? border10 : inner10) += count[t];
    ++(border(t) ? n_border : n_inner);
  }
  const uint32_t b19 = 99;  // t % 20 == 19 and t % 7 == 1
  ASSERT_TRUE(border(b19));
  const double coverage_ratio = expected_weight(state[b19], p.alloc_floor, p.alloc_scale) /
                                expected_weight(state[19], p.alloc_floor, p.alloc_scale);
  EXPECT_LT(coverage_ratio, 0.35);
  EXPECT_NEAR((border10 / n_border) / (inner10 / n_inner), coverage_ratio, 0.02 * coverage_ratio);

  // Deterministic: the same state gives the same keys.
  std::vector<uint32_t> again, weights2;
  allocate(state, p, again, weights2);
  EXPECT_EQ(keys, again);
}

// Injected error: a rule that ignored the error (uniform shares) must fail
// the floor/ceil check above, so that check has teeth.
TEST_F(AdaptiveAllocationTest, UniformSharesWouldFailTheCheck) {
  const std::vector<TexelState> state = crafted_state();
  const cl::LuxBakeParams p = adaptive_params(0.1, 1000.0, 25.0);
  std::vector<uint32_t> keys, weights;
  allocate(state, p, keys, weights);
  if (HasFatalFailure()) return;
  std::vector<uint32_t> count(kTexels, 0);
  for (uint32_t k : keys) ++count[k];
  size_t outside = 0;
  for (uint32_t t = 0; t < kTexels; ++t) {
    const double uniform = double(kBatch) / kTexels;
    if (count[t] < std::floor(uniform) || count[t] > std::ceil(uniform)) ++outside;
  }
  EXPECT_GT(outside, kTexels / 2);
}

// Injected error: the rule without the coverage weight (every texel as if
// wholly on geometry) must fail the per-texel weight check of
// BatchSplitsByRelativeError on the border texels, so that check sees the
// coverage.
TEST_F(AdaptiveAllocationTest, IgnoringCoverageWouldFailTheCheck) {
  const std::vector<TexelState> state = crafted_state();
  const cl::LuxBakeParams p = adaptive_params(0.1, kUnit / 0.05, kUnit * kMix);
  std::vector<uint32_t> keys, weights;
  allocate(state, p, keys, weights);
  if (HasFatalFailure()) return;
  size_t caught = 0, borders = 0;
  for (uint32_t t = 0; t < kTexels; ++t) {
    if (!border(t) || t == 11) continue;
    ++borders;
    const double w = expected_weight(state[t], p.alloc_floor, p.alloc_scale, false);
    if (std::fabs(weights[t] - w) > 0.5 + 1e-3 * w) ++caught;
  }
  EXPECT_EQ(caught, borders);
}

}  // namespace
}  // namespace luxel
