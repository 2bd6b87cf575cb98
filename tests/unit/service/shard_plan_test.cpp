// Coordinator mode without daemons: which bakes are sharded and refused, the
// settings each worker gets, combined progress, the state file, worker lists.
#include "service/coordinator/shard_plan.h"

#include <gtest/gtest.h>

#include <cmath>

#include "service/coordinator/worker_pool.h"

namespace luxel::service::coordinator {
namespace {

v1::BakeSettings sharded(uint32_t n) {
  v1::BakeSettings s;
  s.set_samples_per_texel(64);
  s.set_shards(n);
  return s;
}

TEST(ShardPlan, RefusesWhatCannotBeSharded) {
  EXPECT_TRUE(check_shard_settings(sharded(1), false).is_ok());  // one machine
  EXPECT_TRUE(check_shard_settings(sharded(2), true).is_ok());
  Status no_workers = check_shard_settings(sharded(2), false);
  EXPECT_NE(no_workers.message().find("settings.shards"), std::string::npos);
  v1::BakeSettings auto_on_plain = sharded(0);
  auto_on_plain.set_shards_auto(true);
  EXPECT_NE(check_shard_settings(auto_on_plain, false).message().find("settings.shards_auto"),
            std::string::npos);
  // Time and target error are the coordinator's stop rules, with or without
  // a sample count; a bake with no rule at all is refused.
  v1::BakeSettings no_samples = sharded(2);
  no_samples.set_samples_per_texel(0);
  EXPECT_NE(check_shard_settings(no_samples, true).message().find("settings.samples_per_texel"),
            std::string::npos);
  v1::BakeSettings error = no_samples;
  error.set_target_error(0.01);
  EXPECT_TRUE(check_shard_settings(error, true).is_ok());
  v1::BakeSettings timed = no_samples;
  timed.set_time_budget_s(10);
  EXPECT_TRUE(check_shard_settings(timed, true).is_ok());
  timed.set_samples_per_texel(64);
  EXPECT_TRUE(check_shard_settings(timed, true).is_ok());
  v1::BakeSettings benchmark = sharded(2);
  benchmark.set_reference_bake_id("0123456789abcdef0123456789abcdef");
  EXPECT_NE(check_shard_settings(benchmark, true).message().find("settings.reference_bake_id"),
            std::string::npos);
  v1::BakeSettings adaptive = sharded(2);
  adaptive.set_adaptive(true);
  EXPECT_NE(check_shard_settings(adaptive, true).message().find("settings.adaptive"),
            std::string::npos);
  adaptive.set_adaptive(false);
  EXPECT_TRUE(check_shard_settings(adaptive, true).is_ok());
  v1::BakeSettings given = sharded(2);
  given.set_shard_count(2);
  EXPECT_NE(check_shard_settings(given, true).message().find("settings.shard_count"),
            std::string::npos);
  // Samples are dealt in blocks: 16 per texel leave the second shard none.
  v1::BakeSettings few = sharded(2);
  few.set_samples_per_texel(16);
  EXPECT_NE(check_shard_settings(few, true).message().find("shard"), std::string::npos);
  EXPECT_EQ(usable_shard_count(few, 8, {}), 1u);
  few.set_samples_per_texel(64);
  EXPECT_EQ(usable_shard_count(few, 8, {}), 4u);
  EXPECT_EQ(usable_shard_count(few, 3, {}), 3u);
  // The engine's rule for shards, applied at the coordinator's SubmitBake.
  v1::BakeSettings progressive = sharded(2);
  progressive.add_encodings(v1::ENCODING_SG6);
  progressive.set_solver(v1::SOLVER_PROGRESSIVE);
  EXPECT_FALSE(check_shard_settings(progressive, true).is_ok());
}

TEST(ShardPlan, WorkerSettingsKeepTheWholeSampleCount) {
  v1::BakeSettings s = sharded(3);
  s.set_snapshot_format(v1::SNAPSHOT_FORMAT_PNG);
  const v1::BakeSettings w = shard_settings(s, 2, 3);
  EXPECT_EQ(w.shards(), 0u);
  EXPECT_FALSE(w.shards_auto());
  EXPECT_EQ(w.samples_per_texel(), 64u);
  EXPECT_EQ(w.snapshot_format(), v1::SNAPSHOT_FORMAT_EXR);
  EXPECT_EQ(w.shard_index(), 2u);
  EXPECT_EQ(w.shard_count(), 3u);
  s.set_snapshot_format(v1::SNAPSHOT_FORMAT_NONE);
  EXPECT_EQ(shard_settings(s, 0, 3).snapshot_format(), v1::SNAPSHOT_FORMAT_NONE);
  // The whole bake's time budget and target error stay: each shard's backstop.
  s.set_time_budget_s(30);
  s.set_target_error(0.02);
  EXPECT_EQ(shard_settings(s, 1, 3).time_budget_s(), 30);
  EXPECT_EQ(shard_settings(s, 1, 3).target_error(), 0.02);
}

// The merged bake's termination: the coordinator's rule when it decided
// one, else what the shards ended on (samples only when all did).
TEST(ShardPlan, MergedTermination) {
  using pipeline::Termination;
  ShardPlan p;
  p.count = 2;
  p.shards = {{.index = 0, .termination = "samples"}, {.index = 1, .termination = "samples"}};
  EXPECT_EQ(merged_termination(p), Termination::kSamples);
  p.shards[1].termination = "time";  // a shard's own time backstop
  EXPECT_EQ(merged_termination(p), Termination::kTime);
  p.shards[1].termination = "stopped";
  EXPECT_EQ(merged_termination(p), Termination::kStopped);
  p.stop = "error";
  EXPECT_EQ(merged_termination(p), Termination::kError);
  auto back = plan_from_json(plan_to_json(p));
  ASSERT_TRUE(back.is_ok()) << back.status().to_string();
  EXPECT_EQ(back->stop, "error");
  EXPECT_EQ(back->shards[1].termination, "stopped");
  std::string bad = plan_to_json(p);
  bad.replace(bad.find("\"error\""), 7, "\"never\"");
  EXPECT_EQ(plan_from_json(bad).status().code(), StatusCode::kDataLoss);
}

TEST(ShardPlan, CombinedProgress) {
  v1::BakeProgress a, b;
  a.set_paths(1000);
  a.set_mean_spp(10);
  a.set_min_spp(9);
  a.set_error(0.2);
  a.set_elapsed_s(3);
  a.set_eta_s(1);
  a.set_fraction(0.5);
  b = a;
  b.set_elapsed_s(4);
  b.set_eta_s(2);
  b.set_fraction(1);
  const v1::BakeProgress c = combine_progress({a, b});
  EXPECT_EQ(c.paths(), 2000u);
  EXPECT_DOUBLE_EQ(c.mean_spp(), 20);
  EXPECT_EQ(c.min_spp(), 18u);
  // Two equal halves: the merged mean's standard error is 1/sqrt(2) of each.
  EXPECT_NEAR(c.error(), 0.2 / std::sqrt(2.0), 1e-12);
  EXPECT_DOUBLE_EQ(c.elapsed_s(), 4);
  EXPECT_DOUBLE_EQ(c.eta_s(), 2);
  EXPECT_DOUBLE_EQ(c.fraction(), 0.75);
  b.set_eta_s(-1);
  b.set_error(0);  // no estimate yet
  const v1::BakeProgress d = combine_progress({a, b});
  EXPECT_DOUBLE_EQ(d.eta_s(), -1);
  EXPECT_DOUBLE_EQ(d.error(), 1);
}

TEST(ShardPlan, StateFileRoundTripAndGarbage) {
  ShardPlan p;
  p.count = 2;
  p.shards.resize(2);
  p.shards[0] = {.index = 0, .worker = "127.0.0.1:1", .worker_bake_id = "ab", .attempts = 1};
  p.shards[1] = {.index = 1,
                 .worker = "",
                 .attempts = 2,
                 .downloaded = true,
                 .sha256 = "cd",
                 .bad_workers = {"127.0.0.1:2"}};
  p.abandoned = {{"127.0.0.1:2", "ef"}};
  auto back = plan_from_json(plan_to_json(p));
  ASSERT_TRUE(back.is_ok()) << back.status().to_string();
  EXPECT_EQ(plan_to_json(back.value()), plan_to_json(p));
  EXPECT_EQ(back->shards[1].bad_workers, std::vector<std::string>{"127.0.0.1:2"});
  EXPECT_EQ(plan_from_json("{\"count\": 3, \"shards\": []}").status().code(),
            StatusCode::kDataLoss);
  EXPECT_EQ(plan_from_json("not json").status().code(), StatusCode::kDataLoss);
  EXPECT_NE(shard_idempotency_key("b", 0, 1), shard_idempotency_key("b", 1, 1));
  EXPECT_NE(shard_idempotency_key("b", 0, 1), shard_idempotency_key("b", 0, 2));
}

TEST(WorkerPool, ListsAndNames) {
  auto l = parse_worker_list("a:1,b:2,a:1");
  ASSERT_TRUE(l.is_ok());
  EXPECT_EQ(l.value(), (std::vector<std::string>{"a:1", "b:2"}));
  EXPECT_FALSE(parse_worker_list("a").is_ok());
  EXPECT_FALSE(parse_worker_list("a:x").is_ok());
  EXPECT_FALSE(parse_worker_list(",").is_ok());
  auto local = resolve_workers_dns("localhost:7000");
  ASSERT_TRUE(local.is_ok()) << local.status().to_string();
  ASSERT_FALSE(local->empty());
  for (const auto& a : local.value()) EXPECT_EQ(a.substr(a.size() - 5), ":7000") << a;
  EXPECT_EQ(resolve_workers_dns("no-such-host.invalid").status().code(), StatusCode::kUnavailable);
  WorkerPool pool({.workers = {"x:1"}});
  EXPECT_EQ(pool.resolve(), std::vector<std::string>{"x:1"});
}

}  // namespace
}  // namespace luxel::service::coordinator
