// Internal to the coordinator (coordinator.cpp, sharded_run.cpp,
// shard_driver.cpp): one sharded bake in flight, its shard threads and the
// loop that combines them.
#pragma once

#include <atomic>
#include <condition_variable>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "api/scene_files.h"
#include "common/clock.h"
#include "service/bake_store.h"
#include "service/coordinator/coordinator.h"
#include "service/coordinator/shard_plan.h"
#include "service/coordinator/worker_pool.h"
#include "service/metrics.h"
#include "shards/shard_merge.h"

namespace luxel::service::coordinator {

namespace fs = std::filesystem;

inline constexpr const char* kAccumulators = "accumulators.bin";
inline constexpr size_t kUploadChunkBytes = 64 * 1024;

inline std::string grpc_text(const grpc::Status& s) {
  return strprintf("%d: %s", int(s.error_code()), s.error_message().c_str());
}

// One sharded bake in flight: the shard threads and the loop that combines them.
class Run {
 public:
  Run(BakeStore& bakes, WorkerPool& pool, const CoordinatorOptions& options, const ShardedJob& job)
      : bakes_(bakes), pool_(pool), options_(options), job_(job) {}

  // The sharded bake as named steps (sharded_run.cpp): the plan (the one on
  // disk after a restart, else a new one), one thread per shard
  // (shard_driver.cpp), the combining loop until every shard is downloaded
  // or the bake stops, then the exact merge.
  Result<pipeline::BakeResult> execute();

 private:
  // ---- execute()'s steps
  Status plan_shards();       // a new plan (settings.shards, or the resolved workers)
  Status resume_plan();       // the plan on disk: re-attach, rerun shards lost from disk
  void start_status();        // the fingerprint and each shard's status from the plan
  bool combine_until_done();  // the combining loop; false: stopped before every download
  bool host_stopped();        // CancelBake or daemon shutdown: stop the shard threads
  void check_stop_rules(bool all_done, double progress_every, SteadyClock::time_point& last);
  void maybe_publish_snapshot(double every, SteadyClock::time_point& last, uint64_t& seen);
  Result<pipeline::BakeResult> conclude(bool all_done);
  enum class WatchEnd { kTerminal, kRewatch, kLost, kStall, kGone, kStopped };

  // ---- state shared by the threads (mu_)
  void note(const std::string& line);
  void count(const char* event) {
    if (options_.metrics) options_.metrics->shard_event(event);
  }
  Status persist_locked();
  void fail(const Status& why);
  bool stopped() const { return stop_.load(); }
  void sleep_for(double s);

  // ---- one shard's thread
  void drive(uint32_t k);
  bool assign(uint32_t k);
  grpc::Status ensure_scene(const std::string& worker);
  // A worker that refuses the coordinator's credentials will not take the
  // shard however long it is retried: reassigned at once, remembered for
  // the failure's message. False for any other status.
  bool refused_credentials(uint32_t k, const std::string& worker, const grpc::Status& st);
  WatchEnd watch(uint32_t k, const std::string& worker, const std::string& worker_bake,
                 v1::BakeInfo* terminal, grpc::Status* why);
  void lost(uint32_t k, const std::string& worker, const std::string& worker_bake,
            const std::string& why);
  void reassign(uint32_t k, const std::string& worker, const std::string& why);
  void finished(uint32_t k, const std::string& worker, const v1::BakeInfo& terminal);
  Status download(uint32_t k, const std::string& worker, const std::string& worker_bake,
                  std::string* sha256);

  // ---- stop rules across shards
  void decide_stop(const v1::BakeProgress& combined);
  void ask_to_finish(uint32_t k, const std::string& worker, const std::string& worker_bake);

  // ---- the combining loop
  v1::BakeProgress publish_progress();
  void publish_snapshot();
  // CancelBake (finish: keep what it traced) of a worker's bake, within deadline_s.
  grpc::Status cancel_on(const std::string& worker, const std::string& worker_bake, bool finish,
                         double deadline_s);
  void cancel_workers();
  void cancel_abandoned();
  Status fold_downloaded();
  Result<pipeline::BakeResult> merge();

  std::string shard_path(uint32_t k) const { return dir_ + strprintf("/%u.bin", k); }

  BakeStore& bakes_;
  WorkerPool& pool_;
  const CoordinatorOptions& options_;
  const ShardedJob& job_;
  std::string dir_;          // <bake dir>/shards
  std::string fingerprint_;  // every shard's accumulators carry it
  cli::remote::SceneFiles scene_files_;

  std::mutex mu_;
  ShardPlan plan_;
  std::vector<v1::ShardStatus> status_;
  std::vector<v1::Snapshot> snapshots_;  // newest EXR snapshot per shard
  uint64_t snapshot_changes_ = 0;
  uint32_t previews_ = 0;                            // merged snapshots published
  double preview_s_ = 0;                             // seconds spent decoding and averaging them
  std::map<uint32_t, grpc::ClientContext*> active_;  // open WatchBake calls (TryCancel on stop)
  std::optional<Status> failure_;
  // Per shard, the workers that answered UNAUTHENTICATED or
  // PERMISSION_DENIED, with their message ("worker: CODE: message").
  std::map<uint32_t, std::vector<std::string>> credential_refusals_;
  std::set<std::string> finish_sent_;  // worker bakes asked to finish (this process)
  bool stop_rules_ = false;            // the bake has a time budget or target error
  // The merge as a fold (pipeline::ShardMerger), in shard order, as shards
  // arrive: shard k is folded once shards 0..k are downloaded. Only the
  // combining loop's thread touches it.
  pipeline::ShardMerger merger_;
  double fold_read_s_ = 0, fold_merge_s_ = 0;
  std::atomic<bool> stop_{false};
  std::condition_variable wake_;
};

}  // namespace luxel::service::coordinator
