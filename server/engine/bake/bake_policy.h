// When a bake stops, reports, snapshots and checkpoints, and how far along
// it is. No device and no clock of its own: the scheduler passes the paths
// traced and the seconds elapsed, so every rule can be tested on its own
// (tests/unit/bake/bake_policy_test.cpp).
//
// Stopping rules, the first reached wins: samples per texel (exact: the last
// batch is trimmed), the time budget (checked after each iteration), the
// target error (checked after each iteration, on the metric target_metric
// names), cancellation. Progress reports come every progress_interval_s, and
// after every iteration while a target error is set (the rule needs them).
#pragma once

#include <cstdint>
#include <optional>

#include "bake/bake.h"

namespace luxel::pipeline {

class BakePolicy {
 public:
  // grow_batches: iterations start at learning_batch(covered_texels) paths
  // and grow to the paths already traced (BakeSetup::grow_batches).
  BakePolicy(const BakeSettings& settings, const BakeHooks& hooks, uint64_t covered_texels,
             bool grow_batches = false);

  // The first iterations' size where state learned between iterations
  // matters: 16 samples per covered texel, at least 2^15 paths.
  static uint64_t learning_batch(uint64_t covered_texels);

  // Paths the samples rule needs in all (0: no samples rule).
  uint64_t target_paths() const { return target_paths_; }
  // Paths of the next iteration: the batch (with grow_batches, at most the
  // larger of the learning batch and paths_done), trimmed to the samples
  // rule. A function of its arguments only, so resumed bakes iterate alike.
  uint64_t next_batch(uint64_t capacity, uint64_t paths_done) const;

  // The rules checked before progress statistics: samples, cancellation,
  // time. nullopt: keep going.
  std::optional<Termination> stop_after_iteration(uint64_t paths_done, double elapsed_s,
                                                  bool cancelled) const;
  // Whether progress statistics are computed after this iteration.
  bool report_due(double since_report_s) const;
  // The measure target_error applies to, and whether it is reached.
  double tracked_error(const BakeProgress& p) const;
  bool error_reached(const BakeProgress& p) const;
  bool snapshot_due(double since_snapshot_s) const;
  bool checkpoint_due(double since_checkpoint_s, bool requested) const;

  // Fills p.fraction (towards the nearest rule) and p.eta_s from p's paths,
  // elapsed time and errors. The final report is complete (1, ETA 0).
  void estimate(BakeProgress& p, bool final_report) const;

 private:
  const BakeSettings& settings_;
  double snapshot_interval_s_ = 0;
  double checkpoint_interval_s_ = 0;
  bool snapshots_ = false;
  bool checkpoints_ = false;
  uint64_t target_paths_ = 0;
  uint64_t learning_batch_ = 0;  // 0: iterations do not grow
};

}  // namespace luxel::pipeline
