// Coordinator mode: one bake split by sample index across worker luxelds and
// merged exactly (parallel Welford, shards/shard_merge.h). Kubernetes (or
// whoever starts the daemons) runs the machines; this runs one sharded bake:
//
//   for each shard k of N, on its own thread:
//     pick a worker (WorkerPool::resolve, least loaded, not one that failed
//     this shard) -> GetScene, UploadScene when missing (content id) ->
//     SubmitBake(shard_settings(k, N), key shard_idempotency_key) ->
//     WatchBake (progress and EXR snapshots) -> on SUCCEEDED DownloadResult
//     "accumulators.bin" (sha256 checked) -> read_checkpoint, fingerprint
//     checked -> <bake dir>/shards/<k>.bin
//   meanwhile: progress combined (combine_progress) and the shards' snapshots
//   averaged by paths into the coordinator bake's own (approximate previews)
//   finally: merge_shard_states in shard order -> finish_merged_bake -> the
//   runner writes the outputs as for a local bake.
//
// Durability: <bake dir>/shards.json (shard_plan.h) is rewritten atomically
// before and after every submission and download, so a coordinator killed
// at any point and restarted on the same data dir re-attaches to the worker
// bakes (the runner re-queues its RUNNING bakes) and completes.
//
// Stop rules across shards: samples are dealt (each shard traces its share).
// Time and target error are the coordinator's: it sums the shards' progress
// (combine_progress) and, when the slowest shard has traced time_budget_s,
// or the merged error estimate reaches target_error, or CancelBake asked to
// finish, it records the rule in shards.json and asks every shard bake to
// finish (CancelBake with finish): each ends with what it traced, and the
// merge is the exact union of those sample indices. The shards carry the
// bake's own time_budget_s and target_error too, as backstops that end them
// if the coordinator is gone: one shard alone at the target error is
// already past the merged target.
//
// Faults, each recorded in BakeInfo.notes: a worker whose stream fails is
// retried (GetBake, then WatchBake again) for the grace period (a restarted
// luxeld resumes its bakes from checkpoints); past it, or after a stall (no
// new paths for the stall timeout while RUNNING), or when the worker's bake
// FAILED, or when its accumulators are garbage (hash, checksum, fingerprint,
// shard index), the shard goes to another worker from zero. Shards are
// deterministic, so a reassigned shard gives the same bits.
#pragma once

#include <atomic>
#include <memory>
#include <string>

#include "api/settings_translate.h"
#include "bake/bake.h"
#include "common/status.h"
#include "device/context.h"
#include "service/bake_store.h"
#include "service/coordinator/worker_pool.h"
#include "service/scene_store.h"

namespace luxel::service {
class Metrics;
}

namespace luxel::service::coordinator {

struct CoordinatorOptions {
  WorkerConfig workers;
  double grace_s = 60;        // --worker-grace: how long a lost worker is retried
  double stall_s = 300;       // --worker-stall-timeout: no progress this long = lost
  uint32_t max_attempts = 4;  // per shard; past it the bake FAILS
  SettingsLimits limits;
  Metrics* metrics = nullptr;  // shard events, downloads, merge cost (may be null)
};

// One sharded bake as the runner hands it over.
struct ShardedJob {
  std::string bake_id;
  v1::BakeInfo info;
  const scene::Scene* scene = nullptr;
  std::string scene_main_file;  // the stored scene's main file (uploads to workers)
  std::string scene_name;       // its display name (SceneInfo.name)
  const pipeline::BakeSettings* settings = nullptr;
  device::Context* ctx = nullptr;               // for the final merge and outputs
  const std::atomic<bool>* cancel = nullptr;    // CancelBake or shutdown
  const std::atomic<bool>* by_user = nullptr;   // CancelBake: the worker bakes are cancelled too
  const std::atomic<bool>* finish = nullptr;    // CancelBake with finish: merge what is traced
  const std::atomic<bool>* stopping = nullptr;  // daemon shutdown: workers left running
};

class Coordinator {
 public:
  Coordinator(BakeStore& bakes, CoordinatorOptions options);
  ~Coordinator();
  WorkerPool& pool() { return *pool_; }
  const CoordinatorOptions& options() const { return options_; }
  // Runs the job to its end: the merged result (termination kCancelled when
  // cancelled or stopping), or why it failed.
  Result<pipeline::BakeResult> run(const ShardedJob& job);

 private:
  BakeStore& bakes_;
  const CoordinatorOptions options_;
  std::unique_ptr<WorkerPool> pool_;
};

}  // namespace luxel::service::coordinator
