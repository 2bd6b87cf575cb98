// The bake's stopping, reporting, snapshot and checkpoint rules, and its
// progress estimate, without a device (bake/bake_policy.h).
#include "bake/bake_policy.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

namespace luxel::pipeline {
namespace {

BakeSettings samples_only(uint32_t spp) {
  BakeSettings s;
  s.samples_per_texel = spp;
  s.progress_interval_s = 1.0;
  return s;
}

TEST(BakePolicy, LastBatchIsTrimmedToTheSamplesRule) {
  const BakeSettings s = samples_only(10);
  const BakePolicy p(s, {}, /*covered_texels=*/100);
  EXPECT_EQ(p.target_paths(), 1000u);
  EXPECT_EQ(p.next_batch(256, 0), 256u);
  EXPECT_EQ(p.next_batch(256, 768), 232u);
  EXPECT_EQ(p.next_batch(256, 1000), 0u);
  BakeSettings open = s;
  open.samples_per_texel = 0;
  open.time_budget_s = 5;
  EXPECT_EQ(BakePolicy(open, {}, 100).next_batch(256, 1u << 30), 256u) << "no samples rule";
}

// Iterations that grow (the radiance cache's automatic batch): 16 samples
// per covered texel first (at least 2^15 paths), then at most the paths
// already traced, so the cache holds at least half of each texel's samples
// when an iteration reads it, up to the full batch; the samples rule still
// trims the last.
TEST(BakePolicy, GrowingIterationsDoubleUpToTheBatch) {
  EXPECT_EQ(BakePolicy::learning_batch(100), 1u << 15);
  EXPECT_EQ(BakePolicy::learning_batch(10000), 160000u);
  const BakeSettings s = samples_only(1000);
  const BakePolicy p(s, {}, /*covered_texels=*/4096, /*grow_batches=*/true);
  const uint64_t cap = 1u << 18;
  std::vector<uint64_t> batches;
  for (uint64_t done = 0; batches.size() < 64;) {
    const uint64_t b = p.next_batch(cap, done);
    if (b == 0) break;
    batches.push_back(b);
    done += b;
  }
  const std::vector<uint64_t> expected = {65536, 65536, 131072, 262144};
  ASSERT_GE(batches.size(), expected.size() + 1);
  for (size_t i = 0; i < expected.size(); ++i) EXPECT_EQ(batches[i], expected[i]) << i;
  uint64_t total = 0;
  for (size_t i = 0; i < batches.size(); ++i) {
    total += batches[i];
    if (i + 1 < batches.size()) EXPECT_LE(batches[i + 1], std::max<uint64_t>(65536, total));
  }
  EXPECT_EQ(total, 4096u * 1000) << "the samples rule still ends the bake exactly";
  EXPECT_EQ(BakePolicy(s, {}, 4096).next_batch(cap, 0), cap) << "without growth: the batch";
}

TEST(BakePolicy, SamplesRuleWinsOverCancelAndTime) {
  BakeSettings s = samples_only(4);
  s.time_budget_s = 2;
  const BakePolicy p(s, {}, 10);
  EXPECT_EQ(p.stop_after_iteration(40, 9, true), Termination::kSamples);
  EXPECT_EQ(p.stop_after_iteration(39, 9, true), Termination::kCancelled);
  EXPECT_EQ(p.stop_after_iteration(39, 2.0, false), Termination::kTime);
  EXPECT_FALSE(p.stop_after_iteration(39, 1.99, false).has_value());
}

TEST(BakePolicy, ReportsOnTheIntervalOrEveryIterationForAnErrorTarget) {
  BakeSettings s = samples_only(4);
  s.progress_interval_s = 0.5;
  EXPECT_FALSE(BakePolicy(s, {}, 10).report_due(0.49));
  EXPECT_TRUE(BakePolicy(s, {}, 10).report_due(0.5));
  s.target_error = 0.01;
  EXPECT_TRUE(BakePolicy(s, {}, 10).report_due(0.0)) << "the error rule needs statistics";
}

TEST(BakePolicy, ErrorRuleUsesTheNamedMetric) {
  BakeSettings s = samples_only(0);
  s.target_error = 0.1;
  BakeProgress p;
  p.error = 0.5;
  p.rmse = 0.05;
  p.rel_mse = 0.2;
  EXPECT_FALSE(BakePolicy(s, {}, 10).error_reached(p));
  s.target_metric = ErrorMetric::kRmse;
  EXPECT_TRUE(BakePolicy(s, {}, 10).error_reached(p));
  s.target_metric = ErrorMetric::kRelMse;
  EXPECT_FALSE(BakePolicy(s, {}, 10).error_reached(p));
  EXPECT_DOUBLE_EQ(BakePolicy(s, {}, 10).tracked_error(p), 0.2);
  s.target_error = 0;
  p.rel_mse = 0;
  EXPECT_FALSE(BakePolicy(s, {}, 10).error_reached(p)) << "0 disables the rule";
}

TEST(BakePolicy, SnapshotsAndCheckpointsNeedTheirHooks) {
  const BakeSettings s = samples_only(4);
  BakeHooks h;
  h.snapshot_interval_s = 2;
  h.checkpoint_interval_s = 3;
  EXPECT_FALSE(BakePolicy(s, h, 10).snapshot_due(100)) << "no on_snapshot";
  EXPECT_FALSE(BakePolicy(s, h, 10).checkpoint_due(100, true)) << "no on_checkpoint";
  h.on_snapshot = [](const BakeSnapshot&) {};
  h.on_checkpoint = [](const BakeCheckpoint&) {};
  const BakePolicy p(s, h, 10);
  EXPECT_FALSE(p.snapshot_due(1.9));
  EXPECT_TRUE(p.snapshot_due(2.0));
  EXPECT_FALSE(p.checkpoint_due(2.9, false));
  EXPECT_TRUE(p.checkpoint_due(3.0, false));
  EXPECT_TRUE(p.checkpoint_due(0.0, true)) << "a requested checkpoint comes at once";
  h.checkpoint_interval_s = 0;
  EXPECT_FALSE(BakePolicy(s, h, 10).checkpoint_due(1e9, false)) << "0: no periodic checkpoints";
}

TEST(BakePolicy, EstimateFollowsTheNearestRule) {
  BakeSettings s = samples_only(10);  // 1000 paths over 100 texels
  s.time_budget_s = 100;
  const BakePolicy p(s, {}, 100);
  BakeProgress prog;
  prog.paths = 250;
  prog.elapsed_s = 1.0;  // 250 paths/s: 3 s left by samples, 99 s by time
  p.estimate(prog, false);
  EXPECT_DOUBLE_EQ(prog.fraction, 0.25);
  EXPECT_DOUBLE_EQ(prog.eta_s, 3.0);
  p.estimate(prog, true);
  EXPECT_DOUBLE_EQ(prog.fraction, 1.0);
  EXPECT_DOUBLE_EQ(prog.eta_s, 0.0);
}

TEST(BakePolicy, ErrorEtaAssumesMonteCarloConvergence) {
  BakeSettings s = samples_only(0);
  s.target_error = 0.01;
  BakeProgress prog;
  prog.paths = 100;
  prog.elapsed_s = 1.0;
  prog.error = 0.02;  // 1/sqrt(n): 4x the samples, 300 more paths at 100/s
  BakePolicy(s, {}, 10).estimate(prog, false);
  EXPECT_DOUBLE_EQ(prog.fraction, 0.25);
  EXPECT_DOUBLE_EQ(prog.eta_s, 3.0);
  s.target_metric = ErrorMetric::kRelMse;
  prog.rel_mse = 0.02;  // 1/n: 2x the samples
  BakePolicy(s, {}, 10).estimate(prog, false);
  EXPECT_DOUBLE_EQ(prog.fraction, 0.5);
  EXPECT_DOUBLE_EQ(prog.eta_s, 1.0);
}

}  // namespace
}  // namespace luxel::pipeline
