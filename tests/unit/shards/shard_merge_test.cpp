// Distributed bakes (shards/shard_merge.h, kernels/shared/shard.h): the
// shards' sample indices partition every texel's sequence; N shards merged
// give the bake one machine makes of the same sample indices (same spp,
// means, variances and SH projections up to float rounding); the merge is
// deterministic and order-independent; corrupt or mismatched shards are
// refused with an error naming them; and two deliberately wrong merges
// (means averaged without weights, Chan's between-shard M2 term dropped)
// fail the same comparison, so it can tell a right merge from a wrong one.
// Over 500 lines: exactness, the fold, stops across shards and every refusal
// share one set of shard fixtures.
#include "shards/shard_merge.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <set>

#include "bake/bake.h"
#include "common/hash.h"
#include "device/context.h"
#include "kernels/shared/shard.h"
#include "post/bake_outputs.h"
#include "scene/gltf_import.h"
#include "settings/settings_schema.h"
#include "shards/checkpoint.h"
#include "support/device_context.h"

namespace luxel {
namespace {

using pipeline::BakeCheckpoint;
using pipeline::BakeResult;
using pipeline::BakeSettings;

// 56 = 3 full blocks of 16 and an incomplete one of 8: every shard count
// from 2 to 4 leaves one shard with the short block (and 4 shards get
// 16, 16, 16, 8 samples: unequal weights, which the weighted merge must
// honour).
constexpr uint32_t kSamples = 56;

TEST(ShardSampleIndices, ShardsPartitionTheSequence) {
  for (uint32_t total : {0u, 1u, 15u, 16u, 17u, 40u, 56u, 64u, 100u, 1000u}) {
    for (uint32_t count = 1; count <= 7; ++count) {
      std::set<uint32_t> seen;
      uint32_t sum = 0;
      for (uint32_t k = 0; k < count; ++k) {
        const uint32_t mine = cl::lux_shard_samples(total, k, count);
        sum += mine;
        for (uint32_t i = 0; i < mine; ++i) {
          const uint32_t g = cl::lux_shard_sample_index(i, k, count);
          EXPECT_LT(g, total) << total << " " << k << "/" << count << " i=" << i;
          EXPECT_TRUE(seen.insert(g).second) << "index " << g << " traced twice";
          // Whole aligned blocks of 16 belong to one shard.
          EXPECT_EQ((g / LUX_SHARD_BLOCK) % count, k);
        }
      }
      EXPECT_EQ(sum, total) << total << " over " << count;
      EXPECT_EQ(seen.size(), total);
    }
  }
  // Shard 0 of 1 is the plain sequence.
  for (uint32_t i = 0; i < 100; ++i) EXPECT_EQ(cl::lux_shard_sample_index(i, 0, 1), i);
}

// The bytes of a checkpoint file of an older version: the fields every
// version from 3 has (a 2x1 lightmap, two covered texels), `extra` (the
// fields the version adds) and the checksum.
std::string old_checkpoint(
    const char* magic,
    const std::function<void(const std::function<void(const void*, size_t)>&)>& extra = {}) {
  std::string b = magic;
  auto raw = [&](const void* p, size_t n) { b.append(static_cast<const char*>(p), n); };
  auto pod = [&](const auto& v) { raw(&v, sizeof v); };
  auto vec = [&](const auto& v) {
    pod(static_cast<uint64_t>(v.size()));
    raw(v.data(), v.size() * sizeof(v[0]));
  };
  vec(std::string("fp"));
  pod(uint32_t{2});
  pod(uint32_t{1});
  pod(uint64_t{6});  // paths
  pod(uint32_t{3});  // iteration
  pod(double{1.5});  // elapsed
  pod(uint64_t{0});  // nonfinite
  vec(std::vector<double>{});
  vec(std::vector<cl::float4>{{1, 2, 3, 4}, {5, 6, 7, 8}});
  vec(std::vector<cl::float4>{{0, 0, 0, 0}, {1, 1, 1, 1}});
  vec(std::vector<cl::float2>{{3, 3}, {3, 3}});
  vec(std::vector<uint32_t>{3, 3});
  vec(std::vector<cl::float4>{});  // basis
  vec(std::vector<double>{});      // tile
  if (extra) extra(raw);
  return b + Hasher().add(b).hex();
}

// A version-3 checkpoint (before the shard fields) still reads: a whole
// bake's state (shard 0 of 1) without an encoding layout.
TEST(ShardCheckpoint, VersionThreeFilesStillRead) {
  const std::string b = old_checkpoint("LUXCKPT3");
  const std::string path = ::testing::TempDir() + "/shard_merge_v3.ckpt";
  std::ofstream(path, std::ios::binary) << b;
  auto c = pipeline::read_checkpoint(path);
  ASSERT_TRUE(c) << c.status().to_string();
  EXPECT_EQ(c->fingerprint, "fp");
  EXPECT_EQ(c->shard_index, 0u);
  EXPECT_EQ(c->shard_count, 1u);
  EXPECT_TRUE(c->basis_layout.empty());
  EXPECT_EQ(c->paths_done, 6u);
  EXPECT_EQ(c->mean[1].y, 6.0f);
  // Written back, it is a version-5 file with the same state.
  ASSERT_TRUE(pipeline::write_checkpoint(path, c.value()).is_ok());
  auto again = pipeline::read_checkpoint(path);
  ASSERT_TRUE(again) << again.status().to_string();
  EXPECT_EQ(again->shard_count, 1u);
  EXPECT_EQ(again->spp, c->spp);
}

// A version-4 checkpoint (before the radiance cache and guiding state)
// still reads, with neither; a version-5 file keeps both, and one whose
// cache does not match its texels is refused as corrupt.
TEST(ShardCheckpoint, VersionFourFilesStillReadAndFiveKeepsTheLearnedState) {
  const std::string b = old_checkpoint("LUXCKPT4", [](const auto& raw) {
    const uint32_t shard[2] = {0, 1};  // index, count
    const uint64_t layout_entries = 0;
    raw(shard, sizeof shard);
    raw(&layout_entries, sizeof layout_entries);  // basis layout
  });
  const std::string path = ::testing::TempDir() + "/shard_merge_v4.ckpt";
  std::ofstream(path, std::ios::binary) << b;
  auto c = pipeline::read_checkpoint(path);
  ASSERT_TRUE(c) << c.status().to_string();
  EXPECT_EQ(c->mean[1].y, 6.0f);
  EXPECT_TRUE(c->radiance_cache.empty());
  EXPECT_TRUE(c->guide.empty());

  pipeline::BakeCheckpoint k = c.value();
  k.radiance_cache = {{0.5f, 0.5f, 0.5f, 3}, {0.25f, 0.25f, 0.25f, 2}};
  k.guide.assign(2 * pipeline::kGuideStride, cl::float4{1, 2, 3, 4});
  ASSERT_TRUE(pipeline::write_checkpoint(path, k).is_ok());
  auto five = pipeline::read_checkpoint(path);
  ASSERT_TRUE(five) << five.status().to_string();
  ASSERT_EQ(five->radiance_cache.size(), 2u);
  EXPECT_EQ(five->radiance_cache[1].w, 2.0f);
  ASSERT_EQ(five->guide.size(), 2 * pipeline::kGuideStride);
  EXPECT_EQ(five->guide[5].z, 3.0f);

  k.radiance_cache.resize(1);
  ASSERT_TRUE(pipeline::write_checkpoint(path, k).is_ok());
  auto bad = pipeline::read_checkpoint(path);
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.status().code(), StatusCode::kDataLoss) << bad.status().to_string();
}

std::string error_of(const Status& s) {
  return s.is_ok() ? "" : s.message();
}

TEST(ShardSettings, RefusedCombinationsNameTheField) {
  BakeSettings s = pipeline::default_settings();
  s.adaptive = false;
  s.shard_count = 4;
  s.shard_index = 3;
  EXPECT_EQ(error_of(pipeline::validate_settings(s)), "");
  EXPECT_EQ(s.shard_samples(), 64u);  // 256 = 16 blocks, 4 each
  s.shard_index = 4;
  EXPECT_NE(error_of(pipeline::validate_settings(s)).find("settings.shard_index"),
            std::string::npos);
  s.shard_index = 0;
  s.shard_count = 4097;
  EXPECT_NE(error_of(pipeline::validate_settings(s)).find("settings.shard_count"),
            std::string::npos);
  s.shard_count = 4;
  s.adaptive = true;
  EXPECT_NE(error_of(pipeline::validate_settings(s)).find("settings.adaptive"), std::string::npos);
  s.adaptive = false;
  s.encodings.names = {"sg12"};  // auto: progressive non-negative
  EXPECT_NE(error_of(pipeline::validate_settings(s)).find("settings.solver"), std::string::npos);
  s.encodings.solver = pipeline::EncodingSolver::kProjection;
  EXPECT_EQ(error_of(pipeline::validate_settings(s)), "");
  s.encodings.names = {"sh2"};  // auto: projection
  s.encodings.solver = pipeline::EncodingSolver::kAuto;
  EXPECT_EQ(error_of(pipeline::validate_settings(s)), "");
  s.filter = pipeline::Filter::kGaussian;
  EXPECT_NE(error_of(pipeline::validate_settings(s)).find("settings.filter"), std::string::npos);
  s.filter = pipeline::Filter::kBox;
  // 40 samples make 3 blocks: a 4th shard would have none.
  s.samples_per_texel = 40;
  s.shard_index = 3;
  EXPECT_NE(error_of(pipeline::validate_settings(s)).find("settings.shard_count"),
            std::string::npos);
  // shard_index without sharding.
  s.shard_count = 1;
  s.shard_index = 1;
  EXPECT_NE(error_of(pipeline::validate_settings(s)).find("settings.shard_index"),
            std::string::npos);
}

class ShardMergeTest : public testing::DeviceTest<> {
 protected:
  static void SetUpTestSuite() {
    ASSERT_NO_FATAL_FAILURE(DeviceTest::SetUpTestSuite());
    auto scene = scene::import_gltf_file(std::string(LUXEL_SCENES_DIR) + "/cornell_box.gltf");
    ASSERT_TRUE(scene) << scene.status().to_string();
    scene_ = new scene::Scene(std::move(scene.value()));
    pipeline::BakeHooks h = hooks();
    h.keep_final_state = true;
    auto single = pipeline::bake(*scene_, settings(), *ctx_, h);
    ASSERT_TRUE(single) << single.status().to_string();
    single_ = new BakeResult(std::move(single.value()));
    ASSERT_TRUE(single_->final_state);
  }
  static void TearDownTestSuite() {
    delete single_;
    delete scene_;
    DeviceTest::TearDownTestSuite();
  }
  // The whole bake: uniform, SH2 by projection.
  static BakeSettings settings() {
    BakeSettings s;
    s.atlas.resolution = 32;
    s.samples_per_texel = kSamples;
    s.max_bounces = 2;
    s.paths_per_iteration = 8192;  // several iterations per bake
    s.seed = 7;
    s.adaptive = false;
    s.radiance_cache = false;  // shards trace every path: so does the single bake
    s.encodings.names = {"sh2"};
    return s;
  }
  static pipeline::BakeHooks hooks() {
    pipeline::BakeHooks h;
    h.fingerprint = "cornell-test-bake";  // what the service derives from scene + settings
    return h;
  }
  // The final states of shards 0..count-1.
  static std::vector<BakeCheckpoint> bake_shards(uint32_t count,
                                                 const BakeSettings& whole = settings()) {
    std::vector<BakeCheckpoint> states;
    for (uint32_t k = 0; k < count; ++k) {
      BakeSettings s = whole;
      s.shard_index = k;
      s.shard_count = count;
      auto r = pipeline::bake(*scene_, s, *ctx_, hooks());
      EXPECT_TRUE(r) << r.status().to_string();
      if (!r) return {};
      EXPECT_TRUE(r.value().final_state) << "shard " << k;
      if (!r.value().final_state) return {};
      EXPECT_EQ(r.value().min_spp, s.shard_samples());
      states.push_back(*r.value().final_state);
    }
    return states;
  }
  static Result<BakeResult> finish(const BakeCheckpoint& merged) {
    return pipeline::finish_merged_bake(*scene_, settings(), *ctx_, merged,
                                        pipeline::Termination::kSamples, hooks());
  }

  static scene::Scene* scene_;
  static BakeResult* single_;
};
scene::Scene* ShardMergeTest::scene_ = nullptr;
BakeResult* ShardMergeTest::single_ = nullptr;

// How far a finished merge is from the single bake, in units of the
// tolerance (<= 1: within). Both hold the same sample values (a path's
// value depends only on its texel, sample index and seed), accumulated in
// float in another order and grouping: a running mean of n samples carries
// a rounding error of about n eps max|x| (Higham, Accuracy and Stability,
// §1.9), with n = 56, eps = 6e-8 and max|x| up to ~10x the mean for
// path-traced samples that is ~3e-5 of the mean; we allow 2e-4 relative
// (plus 1e-6 absolute for black texels). The relative error comes from M2
// and the weight sums through a square root: 1e-3. SH coefficients get
// 2e-4 of the texel's largest coefficient, since higher bands cancel.
struct Deviation {
  double irradiance = 0, rel_error = 0, sh = 0;
  bool samples_equal = true;
};

Deviation deviation(const BakeResult& a, const BakeResult& b) {
  Deviation d;
  EXPECT_EQ(a.irradiance.size(), b.irradiance.size());
  EXPECT_EQ(a.rel_error.size(), b.rel_error.size());
  if (a.irradiance.size() != b.irradiance.size() || a.rel_error.size() != b.rel_error.size())
    return {1e9, 1e9, 1e9, false};
  for (size_t i = 0; i < a.irradiance.size(); ++i) {
    const double x = a.irradiance[i], y = b.irradiance[i];
    d.irradiance = std::max(d.irradiance, std::abs(x - y) / (2e-4 * std::abs(y) + 1e-6));
  }
  for (size_t i = 0; i < a.rel_error.size(); ++i) {
    const double x = a.rel_error[i], y = b.rel_error[i];
    d.rel_error = std::max(d.rel_error, std::abs(x - y) / (1e-3 * std::abs(y) + 1e-7));
  }
  d.samples_equal = a.samples == b.samples;
  if (a.encodings.size() != 1 || b.encodings.size() != 1) return {1e9, 1e9, 1e9, false};
  const auto& ca = a.encodings[0].coefficients;
  const auto& cb = b.encodings[0].coefficients;
  const size_t per = static_cast<size_t>(b.encodings[0].count) * 3;
  if (ca.size() != cb.size() || per == 0) return {1e9, 1e9, 1e9, false};
  for (size_t t = 0; t + per <= cb.size(); t += per) {
    double scale = 0;
    for (size_t j = 0; j < per; ++j) scale = std::max(scale, double{std::abs(cb[t + j])});
    for (size_t j = 0; j < per; ++j)
      d.sh = std::max(d.sh, std::abs(double{ca[t + j]} - cb[t + j]) / (2e-4 * scale + 1e-6));
  }
  return d;
}

void expect_same_bits(const BakeCheckpoint& a, const BakeCheckpoint& b) {
  auto same = [](const auto& x, const auto& y) {
    return x.size() == y.size() &&
           (x.empty() || std::memcmp(x.data(), y.data(), x.size() * sizeof(x[0])) == 0);
  };
  EXPECT_TRUE(same(a.mean, b.mean));
  EXPECT_TRUE(same(a.m2, b.m2));
  EXPECT_TRUE(same(a.weight, b.weight));
  EXPECT_TRUE(same(a.spp, b.spp));
  EXPECT_TRUE(same(a.basis, b.basis));
  EXPECT_EQ(a.paths_done, b.paths_done);
}

TEST_F(ShardMergeTest, MergedShardsGiveTheSingleBake) {
  for (uint32_t count = 1; count <= 4; ++count) {
    SCOPED_TRACE(strprintf("%u shard(s)", count));
    // One shard: the whole bake's own state (BakeHooks::keep_final_state).
    std::vector<BakeCheckpoint> states =
        count == 1 ? std::vector<BakeCheckpoint>{*single_->final_state} : bake_shards(count);
    ASSERT_EQ(states.size(), count);
    uint64_t paths = 0;
    for (const BakeCheckpoint& st : states) {
      EXPECT_EQ(st.fingerprint, "cornell-test-bake");
      EXPECT_EQ(st.shard_count, count);
      paths += st.paths_done;
    }
    EXPECT_EQ(paths, single_->paths);
    auto merged = pipeline::merge_shard_states(states);
    ASSERT_TRUE(merged) << merged.status().to_string();
    EXPECT_EQ(merged.value().shard_count, 1u);
    EXPECT_EQ(merged.value().paths_done, single_->paths);
    for (uint32_t n : merged.value().spp) ASSERT_EQ(n, kSamples);
    // The accumulators themselves against the single bake's, every channel.
    const BakeCheckpoint& one = *single_->final_state;
    ASSERT_EQ(merged.value().mean.size(), one.mean.size());
    double worst_mean = 0, worst_m2 = 0, worst_w = 0;
    for (size_t t = 0; t < one.mean.size(); ++t) {
      for (int c = 0; c < 4; ++c) {
        const double a = (&merged.value().mean[t].x)[c], b = (&one.mean[t].x)[c];
        worst_mean = std::max(worst_mean, std::abs(a - b) / (2e-4 * std::abs(b) + 1e-6));
        const double va = (&merged.value().m2[t].x)[c], vb = (&one.m2[t].x)[c];
        worst_m2 = std::max(worst_m2, std::abs(va - vb) / (2e-3 * std::abs(vb) + 1e-6));
      }
      worst_w = std::max({worst_w, std::abs(double{merged.value().weight[t].x} - one.weight[t].x),
                          std::abs(double{merged.value().weight[t].y} - one.weight[t].y)});
      EXPECT_EQ(merged.value().spp[t], one.spp[t]);
    }
    EXPECT_LE(worst_mean, 1.0);
    EXPECT_LE(worst_m2, 1.0);
    EXPECT_EQ(worst_w, 0.0);  // sums of unit weights: exact in float below 2^24

    // Merging twice, and in another order, gives the same bits.
    auto again = pipeline::merge_shard_states(states);
    ASSERT_TRUE(again);
    expect_same_bits(merged.value(), again.value());
    std::vector<BakeCheckpoint> reversed(states.rbegin(), states.rend());
    auto permuted = pipeline::merge_shard_states(reversed);
    ASSERT_TRUE(permuted);
    expect_same_bits(merged.value(), permuted.value());
    // The coordinator's fold, one shard at a time in index order: same bits,
    // on one thread or on several (texel ranges side by side).
    for (unsigned threads : {1u, 3u}) {
      pipeline::ShardMerger fold(threads);
      for (const BakeCheckpoint& st : states) ASSERT_TRUE(fold.add(st).is_ok());
      auto folded = fold.finish();
      ASSERT_TRUE(folded) << folded.status().to_string();
      expect_same_bits(merged.value(), folded.value());
    }

    auto finished = finish(merged.value());
    ASSERT_TRUE(finished) << finished.status().to_string();
    const BakeResult& f = finished.value();
    EXPECT_EQ(f.paths, single_->paths);  // nothing more traced
    EXPECT_EQ(f.min_spp, kSamples);
    EXPECT_EQ(f.termination, pipeline::Termination::kSamples);
    EXPECT_FALSE(f.final_state);
    const Deviation d = deviation(f, *single_);
    EXPECT_TRUE(d.samples_equal);
    EXPECT_LE(d.irradiance, 1.0);
    EXPECT_LE(d.rel_error, 1.0);
    EXPECT_LE(d.sh, 1.0);
    EXPECT_NEAR(f.error, single_->error, 1e-3 * single_->error);
    std::printf(
        "%u shard(s): deviation / tolerance: state mean %.3g, M2 %.3g; irradiance %.3g, "
        "rel_error %.3g, sh2 %.3g\n",
        count, worst_mean, worst_m2, d.irradiance, d.rel_error, d.sh);

    if (count != 4) continue;
    // Negative controls on the 16/16/16/8 split. (1) Means averaged without
    // their weights.
    BakeCheckpoint unweighted = merged.value();
    for (size_t t = 0; t < unweighted.mean.size(); ++t) {
      float* m = &unweighted.mean[t].x;
      for (int c = 0; c < 4; ++c) {
        double sum = 0;
        for (const BakeCheckpoint& st : states) sum += (&st.mean[t].x)[c];
        m[c] = static_cast<float>(sum / count);
      }
    }
    auto wrong_mean = finish(unweighted);
    ASSERT_TRUE(wrong_mean) << wrong_mean.status().to_string();
    const Deviation dm = deviation(wrong_mean.value(), *single_);
    EXPECT_GT(dm.irradiance, 10.0) << "an unweighted mean went unnoticed";
    // (2) M2 without Chan's between-shard term d^2 Wa Wb / W.
    BakeCheckpoint no_between = merged.value();
    for (size_t t = 0; t < no_between.m2.size(); ++t) {
      float* m2 = &no_between.m2[t].x;
      for (int c = 0; c < 4; ++c) {
        double sum = 0;
        for (const BakeCheckpoint& st : states) sum += (&st.m2[t].x)[c];
        m2[c] = static_cast<float>(sum);
      }
    }
    auto wrong_m2 = finish(no_between);
    ASSERT_TRUE(wrong_m2) << wrong_m2.status().to_string();
    const Deviation dv = deviation(wrong_m2.value(), *single_);
    EXPECT_LE(dv.irradiance, 1.0);
    EXPECT_GT(dv.rel_error, 10.0) << "a dropped between-shard M2 term went unnoticed";
    std::printf("negative controls: unweighted mean %.3g, M2 without the between term %.3g\n",
                dm.irradiance, dv.rel_error);

    // The accumulators survive the artifact format.
    const std::string path = ::testing::TempDir() + "/shard_merge_accumulators.bin";
    ASSERT_TRUE(pipeline::write_checkpoint(path, states[3]).is_ok());
    auto read = pipeline::read_checkpoint(path);
    ASSERT_TRUE(read) << read.status().to_string();
    EXPECT_EQ(read.value().shard_index, 3u);
    EXPECT_EQ(read.value().shard_count, 4u);
    EXPECT_EQ(read.value().basis_layout, states[3].basis_layout);
    expect_same_bits(read.value(), states[3]);
  }
}

// A shard baked in device-memory tiles (bake/tile_plan.h) ends with
// the state of every tile, the same bits as untiled; a merged state
// finishes in tiles too, with the bits of the untiled finish.
// Stops by time, error or request end each shard wherever it is: the
// shards hold different numbers of samples, and texels within one shard may
// differ by one. The merge is still exactly the union of the sample indices
// they traced: counts add texel by texel, nothing more is traced when
// finishing, and the estimate is unbiased (pooled against the whole bake).
TEST_F(ShardMergeTest, ShardsStoppedEarlyMergeToTheUnionOfTheirSamples) {
  constexpr uint32_t kCount = 3;
  // Shares of 80-96 samples per texel: far more than the iterations below trace.
  BakeSettings whole = settings();
  whole.samples_per_texel = 256;
  std::vector<BakeCheckpoint> states;
  uint64_t paths = 0;
  for (uint32_t k = 0; k < kCount; ++k) {
    BakeSettings s = whole;
    s.shard_index = k;
    s.shard_count = kCount;
    s.progress_interval_s = 1e-9;  // a report after every iteration
    std::atomic<bool> finish{false};
    uint32_t reports = 0;
    pipeline::BakeHooks h = hooks();
    h.finish_now = &finish;
    // Shard k stops after k + 1 iterations of 8192 paths.
    h.on_progress = [&](const pipeline::BakeProgress&) {
      if (++reports == k + 1) finish = true;
      return true;
    };
    auto r = pipeline::bake(*scene_, s, *ctx_, h);
    ASSERT_TRUE(r) << r.status().to_string();
    EXPECT_EQ(r.value().termination, pipeline::Termination::kStopped);
    EXPECT_STREQ(pipeline::termination_name(r.value().termination), "stopped");
    EXPECT_EQ(r.value().paths, uint64_t{k + 1} * 8192);
    ASSERT_TRUE(r.value().final_state) << "a stopped shard keeps its accumulators";
    EXPECT_LT(r.value().min_spp, s.shard_samples());
    paths += r.value().paths;
    states.push_back(*r.value().final_state);
  }
  auto merged = pipeline::merge_shard_states(states);
  ASSERT_TRUE(merged) << merged.status().to_string();
  EXPECT_EQ(merged.value().paths_done, paths);
  for (size_t t = 0; t < merged.value().spp.size(); ++t) {
    uint32_t sum = 0;
    for (const BakeCheckpoint& st : states) sum += st.spp[t];
    ASSERT_EQ(merged.value().spp[t], sum) << "texel slot " << t;
  }
  // Ending on samples needs every texel at the count: refused, naming it.
  auto as_samples = pipeline::finish_merged_bake(*scene_, whole, *ctx_, merged.value(),
                                                 pipeline::Termination::kSamples, hooks());
  ASSERT_FALSE(as_samples);
  EXPECT_NE(as_samples.status().message().find("settings.samples_per_texel"), std::string::npos);
  for (auto why : {pipeline::Termination::kTime, pipeline::Termination::kError,
                   pipeline::Termination::kStopped}) {
    auto f = pipeline::finish_merged_bake(*scene_, whole, *ctx_, merged.value(), why, hooks());
    ASSERT_TRUE(f) << f.status().to_string();
    EXPECT_EQ(f.value().termination, why);
    EXPECT_EQ(f.value().paths, paths);  // nothing more traced
    // Unbiased: the pooled irradiance agrees with the whole 56-sample bake.
    // Both estimate one expectation from overlapping sample indices; the
    // merged one has 6 x 8192 paths over the covered texels (about as many
    // per texel as the whole bake), and the pooled relative standard error
    // of either is below 1 %.
    double merged_sum = 0, single_sum = 0;
    for (size_t i = 0; i < single_->irradiance.size(); i += 4) {
      merged_sum +=
          f.value().irradiance[i] + f.value().irradiance[i + 1] + f.value().irradiance[i + 2];
      single_sum +=
          single_->irradiance[i] + single_->irradiance[i + 1] + single_->irradiance[i + 2];
    }
    EXPECT_NEAR(merged_sum / single_sum, 1.0, 0.03);
  }
  // More samples in a texel than the bake allows: shards of another bake.
  BakeSettings fewer = settings();
  fewer.samples_per_texel = 16;
  auto over = pipeline::finish_merged_bake(*scene_, fewer, *ctx_, merged.value(),
                                           pipeline::Termination::kTime, hooks());
  ASSERT_FALSE(over);
  EXPECT_NE(over.status().message().find("more than the bake's 16"), std::string::npos);
}

// finish_now on a whole bake: set before the first iteration, it ends with
// nothing traced (a queued bake asked to finish); set later, after the
// current iteration, with a complete result of what was traced.
TEST_F(ShardMergeTest, FinishNowEndsAWholeBakeWithWhatItTraced) {
  std::atomic<bool> finish{true};
  pipeline::BakeHooks h = hooks();
  h.finish_now = &finish;
  auto none = pipeline::bake(*scene_, settings(), *ctx_, h);
  ASSERT_TRUE(none) << none.status().to_string();
  EXPECT_EQ(none.value().termination, pipeline::Termination::kStopped);
  EXPECT_EQ(none.value().paths, 0u);
  EXPECT_EQ(none.value().min_spp, 0u);

  finish = false;
  BakeSettings s = settings();
  s.progress_interval_s = 1e-9;
  int reports = 0;
  h.on_progress = [&](const pipeline::BakeProgress&) {
    if (++reports == 2) finish = true;
    return true;
  };
  auto two = pipeline::bake(*scene_, s, *ctx_, h);
  ASSERT_TRUE(two) << two.status().to_string();
  EXPECT_EQ(two.value().termination, pipeline::Termination::kStopped);
  EXPECT_EQ(two.value().paths, 2u * 8192);
  EXPECT_EQ(two.value().samples.size(), single_->samples.size());
  EXPECT_GT(two.value().error, single_->error);  // fewer samples, larger error estimate
}

TEST_F(ShardMergeTest, TiledShardsAndTiledFinish) {
  // A budget leaving room for about a quarter of the per-texel state
  // (tiled_bake_test's rule).
  const double per_slot = 57.0 + static_cast<double>(single_->basis_bytes_per_texel);
  const double state = per_slot * static_cast<double>(single_->covered_texels);
  const double budget =
      (static_cast<double>(single_->peak_device_bytes) - 0.75 * state) / 1048576.0;
  std::vector<BakeCheckpoint> untiled = bake_shards(2);
  ASSERT_EQ(untiled.size(), 2u);
  BakeSettings s = settings();
  s.shard_index = 1;
  s.shard_count = 2;
  s.device_memory_budget_mib = budget;
  auto tiled = pipeline::bake(*scene_, s, *ctx_, hooks());
  ASSERT_TRUE(tiled) << tiled.status().to_string();
  EXPECT_GE(tiled.value().tiles, 2u);
  ASSERT_TRUE(tiled.value().final_state);
  expect_same_bits(*tiled.value().final_state, untiled[1]);

  auto merged = pipeline::merge_shard_states({untiled[0], *tiled.value().final_state});
  ASSERT_TRUE(merged) << merged.status().to_string();
  auto plain = finish(merged.value());
  ASSERT_TRUE(plain) << plain.status().to_string();
  BakeSettings whole = settings();
  whole.device_memory_budget_mib = budget;
  auto in_tiles = pipeline::finish_merged_bake(*scene_, whole, *ctx_, merged.value(),
                                               pipeline::Termination::kSamples, hooks());
  ASSERT_TRUE(in_tiles) << in_tiles.status().to_string();
  EXPECT_GE(in_tiles.value().tiles, 2u);
  EXPECT_EQ(in_tiles.value().paths, plain.value().paths);
  EXPECT_EQ(in_tiles.value().irradiance, plain.value().irradiance);
  EXPECT_EQ(in_tiles.value().rel_error, plain.value().rel_error);
  EXPECT_EQ(in_tiles.value().samples, plain.value().samples);
  EXPECT_EQ(in_tiles.value().encodings[0].coefficients, plain.value().encodings[0].coefficients);
  EXPECT_EQ(in_tiles.value().min_spp, kSamples);
  // The error summary sums per-tile partials in another order.
  EXPECT_NEAR(in_tiles.value().error, plain.value().error, 1e-6 * plain.value().error);
}

// The weighted parts of the merge (sum w, sum w^2, Wa Wb / W), which box
// bakes (unit weights) leave untouched: synthetic weighted samples
// accumulated per shard with the kernel's float Welford update
// (kernels/bake/accumulate.h lux_welford, West 1979), merged, against one
// accumulator fed them all; the unweighted-mean merge must fail the check.
void welford(const float* x, float w, cl::float4& mean, cl::float4& m2, cl::float2& weight) {
  const float w_new = weight.x + w;
  float* m = &mean.x;
  float* v = &m2.x;
  for (int c = 0; c < 4; ++c) {
    const float delta = x[c] - m[c];
    m[c] += delta * (w / w_new);
    v[c] += w * delta * (x[c] - m[c]);
  }
  weight = {w_new, weight.y + w * w};
}

TEST(ShardMergeWeighted, WeightedWelfordStatesMergeToOneAccumulator) {
  constexpr size_t kTexels = 64;
  constexpr uint32_t kCount = 3;
  uint64_t rng = 12345;
  auto uniform = [&] {
    rng = rng * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<float>((rng >> 40) * 0x1p-24);
  };
  BakeCheckpoint one;
  std::vector<BakeCheckpoint> shards(kCount);
  for (uint32_t k = 0; k < kCount; ++k) {
    shards[k].fingerprint = "synthetic";
    shards[k].shard_index = k;
    shards[k].shard_count = kCount;
    shards[k].width = shards[k].height = 8;
  }
  for (BakeCheckpoint* c : {&one, &shards[0], &shards[1], &shards[2]}) {
    c->mean.assign(kTexels, {});
    c->m2.assign(kTexels, {});
    c->weight.assign(kTexels, {});
    c->spp.assign(kTexels, 0);
  }
  for (size_t t = 0; t < kTexels; ++t) {
    const float level = 0.1f + 10.0f * uniform();
    // Unequal shares (the shards' 16/16/8 blocks), samples with a heavy tail.
    for (uint32_t i = 0; i < 40; ++i) {
      const uint32_t k = i < 16 ? 0 : (i < 32 ? 1 : 2);
      float x[4];
      for (float& v : x) v = level * (uniform() < 0.1f ? 8.0f * uniform() : uniform());
      const float w = 0.05f + 0.95f * uniform();
      welford(x, w, one.mean[t], one.m2[t], one.weight[t]);
      welford(x, w, shards[k].mean[t], shards[k].m2[t], shards[k].weight[t]);
      ++one.spp[t];
      ++shards[k].spp[t];
      ++shards[k].paths_done;
    }
  }
  auto merged = pipeline::merge_shard_states(shards);
  ASSERT_TRUE(merged) << merged.status().to_string();
  auto worst = [&](const BakeCheckpoint& m) {
    double d = 0;
    for (size_t t = 0; t < kTexels; ++t) {
      for (int c = 0; c < 4; ++c) {
        const double a = (&m.mean[t].x)[c], b = (&one.mean[t].x)[c];
        d = std::max(d, std::abs(a - b) / (2e-4 * std::abs(b) + 1e-6));
        const double va = (&m.m2[t].x)[c], vb = (&one.m2[t].x)[c];
        d = std::max(d, std::abs(va - vb) / (2e-3 * std::abs(vb) + 1e-6));
      }
      for (int c = 0; c < 2; ++c) {
        const double a = (&m.weight[t].x)[c], b = (&one.weight[t].x)[c];
        d = std::max(d, std::abs(a - b) / (1e-5 * std::abs(b)));
      }
      EXPECT_EQ(m.spp[t], one.spp[t]);
    }
    return d;
  };
  const double right = worst(merged.value());
  EXPECT_LE(right, 1.0);
  // Negative control: the means averaged without weights.
  BakeCheckpoint unweighted = merged.value();
  for (size_t t = 0; t < kTexels; ++t)
    for (int c = 0; c < 4; ++c) {
      double sum = 0;
      for (const BakeCheckpoint& s : shards) sum += (&s.mean[t].x)[c];
      (&unweighted.mean[t].x)[c] = static_cast<float>(sum / kCount);
    }
  const double wrong = worst(unweighted);
  EXPECT_GT(wrong, 10.0);
  std::printf("weighted synthetic: deviation / tolerance %.3g; unweighted means %.3g\n", right,
              wrong);
}

// A tiled shard checkpoints with its shard fields and resumes from a later
// tile's checkpoint to the same final state; another shard may not resume it.
TEST_F(ShardMergeTest, TiledShardResumesFromItsCheckpoint) {
  BakeSettings s = settings();
  s.shard_index = 1;
  s.shard_count = 2;
  s.paths_per_iteration = 1024;  // several iterations per tile
  auto probe = pipeline::bake(*scene_, s, *ctx_, hooks());
  ASSERT_TRUE(probe) << probe.status().to_string();
  ASSERT_TRUE(probe.value().final_state);
  const double per_slot = 57.0 + static_cast<double>(probe.value().basis_bytes_per_texel);
  const double state = per_slot * static_cast<double>(probe.value().covered_texels);
  s.device_memory_budget_mib =
      (static_cast<double>(probe.value().peak_device_bytes) - 0.75 * state) / 1048576.0;
  // Periodic checkpoints on the way, kept from the second tile on.
  pipeline::BakeHooks h = hooks();
  h.checkpoint_interval_s = 1e-9;
  std::vector<BakeCheckpoint> checkpoints;
  h.on_checkpoint = [&](const BakeCheckpoint& c) {
    if (!c.tile.empty() && c.tile[pipeline::kTileIndex] >= 1) checkpoints.push_back(c);
  };
  auto tiled = pipeline::bake(*scene_, s, *ctx_, h);
  ASSERT_TRUE(tiled) << tiled.status().to_string();
  EXPECT_GE(tiled.value().tiles, 2u);
  ASSERT_TRUE(tiled.value().final_state);
  const BakeCheckpoint& untiled = *probe.value().final_state;
  expect_same_bits(*tiled.value().final_state, untiled);
  // A shard resumed from a checkpoint of a later tile (through the file
  // format) ends with the same state.
  ASSERT_FALSE(checkpoints.empty());
  const std::string path = ::testing::TempDir() + "/shard_merge_tiled.ckpt";
  ASSERT_TRUE(pipeline::write_checkpoint(path, checkpoints.front()).is_ok());
  auto read = pipeline::read_checkpoint(path);
  ASSERT_TRUE(read) << read.status().to_string();
  EXPECT_EQ(read->shard_index, 1u);
  EXPECT_EQ(read->shard_count, 2u);
  pipeline::BakeHooks resume = hooks();
  resume.resume = &read.value();
  auto resumed = pipeline::bake(*scene_, s, *ctx_, resume);
  ASSERT_TRUE(resumed) << resumed.status().to_string();
  ASSERT_TRUE(resumed.value().final_state);
  expect_same_bits(*resumed.value().final_state, untiled);
  // Another shard's checkpoint is refused.
  BakeSettings other = s;
  other.shard_index = 0;
  auto refused = pipeline::bake(*scene_, other, *ctx_, resume);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.status().message().find("checkpoint is shard 1 of 2"), std::string::npos)
      << refused.status().message();
}

TEST_F(ShardMergeTest, CorruptOrMismatchedShardsAreRefusedByName) {
  const std::vector<BakeCheckpoint> good = bake_shards(3);
  ASSERT_EQ(good.size(), 3u);
  auto refused = [&](std::vector<BakeCheckpoint> shards, const std::string& expected) {
    auto r = pipeline::merge_shard_states(std::move(shards));
    ASSERT_FALSE(r) << "accepted; expected: " << expected;
    EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
    EXPECT_NE(r.status().message().find(expected), std::string::npos) << r.status().message();
  };
  {
    auto s = good;
    s[1].fingerprint = "another-bake";
    refused(s, "shard 1 of 3 (input 1): belongs to another bake");
  }
  {
    auto s = good;
    s[2].mean[5].y = std::nanf("");
    refused(s, "shard 2 of 3 (input 2): texel slot 5 holds a non-finite accumulator");
  }
  {
    auto s = good;
    s[2] = s[0];
    refused(s, "shard 0 of 3 (input 2): duplicates input 0");
  }
  {
    auto s = good;
    s.erase(s.begin() + 1);
    refused(s, "shard 1 of 3 is missing");
  }
  {
    auto s = good;
    s[0].spp[0] += 1;
    refused(s, "shard 0 of 3 (input 0): its texels hold");
  }
  {
    auto s = good;
    s[1].m2.pop_back();
    refused(s, "shard 1 of 3 (input 1): array sizes disagree");
  }
  {
    auto s = good;
    s[0].basis_layout[0] |= 1u << 16;  // progressive state
    refused(s, "shard 0 of 3 (input 0): holds progressive");
  }
  refused({}, "no shard states");
  {
    // The fold takes shards in index order, and finishes only with all.
    pipeline::ShardMerger fold;
    Status early = fold.add(good[1]);
    EXPECT_NE(early.message().find("shard 1 of 3: arrives out of order: shard 0 is next"),
              std::string::npos)
        << early.to_string();
    ASSERT_TRUE(fold.add(good[0]).is_ok());
    ASSERT_TRUE(fold.add(good[1]).is_ok());
    auto short_one = fold.finish();
    ASSERT_FALSE(short_one);
    EXPECT_NE(short_one.status().message().find("shard 2 of 3 is missing"), std::string::npos);
    auto other = good[0];
    other.fingerprint = "another bake";
    ASSERT_TRUE(fold.add(good[0]).is_ok());  // reusable after finish()
    EXPECT_NE(fold.add(other).message().find("belongs to another bake"), std::string::npos);
  }
  auto merged = pipeline::merge_shard_states(good);
  ASSERT_TRUE(merged);
  // The finished merge goes through the denoiser and the output writer like
  // any bake (the daemon's default denoise is atrous); no accumulators.bin.
  BakeSettings denoised = settings();
  denoised.denoise = pipeline::Denoise::kAtrous;
  auto finished = pipeline::finish_merged_bake(*scene_, denoised, *ctx_, merged.value(),
                                               pipeline::Termination::kSamples, hooks());
  ASSERT_TRUE(finished) << finished.status().to_string();
  EXPECT_EQ(finished.value().irradiance_denoised.size(), finished.value().irradiance.size());
  const std::string out = ::testing::TempDir() + "/shard_merge_outputs";
  auto written = pipeline::write_bake_outputs(out, *scene_, denoised, finished.value());
  ASSERT_TRUE(written) << written.status().to_string();
  const auto& files = written.value().files;
  EXPECT_NE(std::find(files.begin(), files.end(), "manifest.json"), files.end());
  EXPECT_NE(std::find(files.begin(), files.end(), "sh2.exr"), files.end());
  EXPECT_EQ(std::find(files.begin(), files.end(), "accumulators.bin"), files.end());
  // A merge missing samples is refused when finishing.
  BakeSettings more = settings();
  more.samples_per_texel = kSamples + 16;
  auto r = pipeline::finish_merged_bake(*scene_, more, *ctx_, merged.value(),
                                        pipeline::Termination::kSamples, hooks());
  ASSERT_FALSE(r);
  EXPECT_NE(r.status().message().find("settings.samples_per_texel"), std::string::npos);
}

}  // namespace
}  // namespace luxel
