// The pure parts of coordinator mode, testable without daemons: which bakes
// are sharded, what each worker is asked to bake, how the workers' progress
// becomes the coordinator bake's, and the coordinator's state on disk.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "api/settings_translate.h"
#include "bake/bake.h"
#include "common/status.h"
#include "luxel/v1/luxel.pb.h"

namespace luxel::service::coordinator {

// settings.shards > 1 or settings.shards_auto.
bool is_sharded(const v1::BakeSettings& s);

// SubmitBake's rules for sharded settings on this daemon (INVALID_ARGUMENT
// naming the field): a coordinator (have_workers) is needed; benchmark mode
// is refused (reference_bake_id lives on the coordinator, and with it the
// rmse / rel_mse target metrics), so is adaptive = true (shards sample
// uniformly, each tracing its part of every texel's sample indices; adaptive
// unset is off for them). Any stop rule works: samples are dealt, time and
// target error are decided by the coordinator (coordinator.h). Then the
// engine's own rules for a shard of these settings (the progressive
// least-squares solvers do not merge), as a worker would apply them.
// `auto_count`: the shards shards_auto would make now (the workers resolved).
Status check_shard_settings(const v1::BakeSettings& s, bool have_workers,
                            const SettingsLimits& limits = {}, uint32_t auto_count = 2);

// shards_auto: at most `wanted` shards, fewer where the engine would leave
// the last shard without samples (samples are dealt in blocks).
uint32_t usable_shard_count(const v1::BakeSettings& s, uint32_t wanted,
                            const SettingsLimits& limits);

// What worker `index` of `count` bakes: the whole bake's settings (all of
// samples_per_texel: the engine takes shard index's share of it; the time
// budget and target error as backstops, see coordinator.h) with
// shard_index/shard_count set, shards cleared (a worker never coordinates),
// and EXR snapshots (the coordinator merges them into its previews) unless
// the bake has none.
v1::BakeSettings shard_settings(const v1::BakeSettings& s, uint32_t index, uint32_t count);

// The coordinator bake's progress from its shards': paths and spp summed
// (shares of one texel's samples add up), the relative error of the merged
// mean from the shards' by inverse-variance weighting (1/e^2 = sum 1/e_k^2,
// shards with no estimate yet left out), elapsed and ETA the slowest shard's,
// fraction the mean. Shards not started count as zero progress.
v1::BakeProgress combine_progress(const std::vector<v1::BakeProgress>& shards);

// The idempotency key of shard `index`'s attempt `attempt` (1-based): a
// restarted coordinator that submits again gets the same worker bake back.
std::string shard_idempotency_key(const std::string& bake_id, uint32_t index, uint32_t attempt);

// What the coordinator keeps on disk per bake (<bake dir>/shards.json,
// written atomically at each change): enough to re-attach after a restart.
struct ShardRecord {
  uint32_t index = 0;
  std::string worker;          // host:port; empty: not assigned
  std::string worker_bake_id;  // empty: not submitted
  uint32_t attempts = 0;
  bool downloaded = false;               // <bake dir>/shards/<index>.bin is checked
  std::string sha256;                    // of that file
  std::vector<std::string> bad_workers;  // refused or lost this shard: tried last
  std::string termination;               // the downloaded shard bake's ("samples", "stopped", ...)
};
struct ShardPlan {
  uint32_t count = 0;
  std::vector<ShardRecord> shards;
  // Worker bakes of reassigned shards, {worker, bake id}, not yet cancelled
  // (their worker was down): a worker that comes back would resume them.
  std::vector<std::pair<std::string, std::string>> abandoned;
  // The stop rule the coordinator decided ("time", "error", "stopped"; empty
  // while the shards run on): every shard bake is asked to finish.
  std::string stop;
};
// The merged bake's termination: the coordinator's stop rule when it
// decided one, else the shards' (all "samples": samples; else the first of
// time, error, stopped that a shard ended on).
pipeline::Termination merged_termination(const ShardPlan& plan);
std::string plan_to_json(const ShardPlan& plan);
Result<ShardPlan> plan_from_json(const std::string& text);

}  // namespace luxel::service::coordinator
