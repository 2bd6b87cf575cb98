// Runs queued bakes on worker threads (--max-concurrent-bakes of them).
//
// Each worker owns its device::Context (an OpenCL context is not shared
// between threads) and runs one bake at a time through pipeline::bake with
// hooks that: publish progress into the BakeStore (memory), store the newest
// snapshot in the bake's slot (watchers encode it), write checkpoints, and
// watch the cancel flag. The bake thread never waits for a watcher.
//
// Durability (the daemon may die at any point):
//   - every state change is written to the record before it is reported;
//   - checkpoints every --checkpoint-interval seconds (shards/checkpoint.h,
//     atomic and checksummed);
//   - results are written into results.partial/ and renamed to results/
//     before the record says SUCCEEDED;
//   - at startup, RUNNING records become INTERRUPTED and, with QUEUED and
//     INTERRUPTED ones, are queued again; a resumed bake continues from its
//     checkpoint (same bits as an uninterrupted bake), a torn checkpoint
//     restarts it from zero with a note in the record.
// Graceful shutdown: running bakes write a checkpoint at once, stop, and are
// left INTERRUPTED (resumed by the next start).
#pragma once

#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "accel/intersector.h"
#include "api/settings_translate.h"
#include "device/context.h"
#include "service/bake_store.h"
#include "service/job_queue.h"
#include "service/scene_store.h"

namespace luxel::service {

class Metrics;
namespace coordinator {
class Coordinator;
}

struct RunnerOptions {
  int max_concurrent_bakes = 1;
  std::string device_spec;  // device::choose_device spec ("" = default)
  // What settings.intersector = auto runs on (luxeld --intersector); the
  // fingerprint keeps "auto", so shards of one bake may run on workers with
  // other backends and still merge.
  accel::IntersectorKind auto_intersector = accel::IntersectorKind::kAuto;
  double checkpoint_interval_s = 10;  // 0: no checkpoints
  SettingsLimits limits;
  Metrics* metrics = nullptr;  // progress and finished bakes (metrics.h); may be null
  // Coordinator mode (--workers): sharded bakes run through it instead of the
  // local engine (coordinator/coordinator.h); null on a plain daemon.
  coordinator::Coordinator* coordinator = nullptr;
};

class BakeRunner {
 public:
  BakeRunner(SceneStore& scenes, BakeStore& bakes, JobQueue& queue, RunnerOptions options);
  ~BakeRunner();

  // Startup recovery (see above); call before start().
  Status recover();
  void start();
  // Cancels a queued or running bake; a finished one is returned unchanged.
  // Waits up to 5 s for a running bake to stop. NOT_FOUND for an unknown id.
  // finish: keep the bake instead; it stops after its current iteration and
  // completes from what it has traced (pipeline::BakeHooks::finish_now), or,
  // queued, as soon as it starts. Recorded (BakeInfo.finish_requested) so a
  // restart honours it; returns at once.
  Result<v1::BakeInfo> cancel(const std::string& bake_id, bool finish = false);
  // Graceful stop: no new bakes start; running ones checkpoint and stop
  // (INTERRUPTED). Returns when every worker has exited.
  void shutdown();

  uint64_t paths_traced() const { return paths_traced_.load(); }
  const RunnerOptions& options() const { return options_; }

 private:
  struct Running {
    std::atomic<bool> cancel{false};
    std::atomic<bool> by_user{false};  // CancelBake, as opposed to shutdown
    std::atomic<bool> finish{false};   // CancelBake with finish: end with what is traced
  };
  void worker_loop();
  void run_bake(const std::string& bake_id, std::unique_ptr<device::Context>& ctx,
                Running& running);
  void finish_failed(const std::string& bake_id, const Status& why);

  SceneStore& scenes_;
  BakeStore& bakes_;
  JobQueue& queue_;
  const RunnerOptions options_;
  std::mutex mu_;
  std::mutex device_turn_;  // held by a bake for each iteration (pipeline::BakeHooks)
  std::map<std::string, std::shared_ptr<Running>> running_;
  std::atomic<bool> shutting_down_{false};
  std::vector<std::thread> workers_;
  std::atomic<uint64_t> paths_traced_{0};
};

}  // namespace luxel::service
