#include "bake/bake_policy.h"

#include <algorithm>
#include <cmath>

namespace luxel::pipeline {

const char* termination_name(Termination t) {
  switch (t) {
    case Termination::kSamples:
      return "samples";
    case Termination::kTime:
      return "time";
    case Termination::kError:
      return "error";
    case Termination::kCancelled:
      return "cancelled";
    case Termination::kStopped:
      return "stopped";
  }
  return "?";
}

BakePolicy::BakePolicy(const BakeSettings& settings, const BakeHooks& hooks,
                       uint64_t covered_texels, bool grow_batches)
    : settings_(settings),
      snapshot_interval_s_(hooks.snapshot_interval_s),
      checkpoint_interval_s_(hooks.checkpoint_interval_s),
      snapshots_(static_cast<bool>(hooks.on_snapshot) && hooks.snapshot_interval_s > 0),
      checkpoints_(static_cast<bool>(hooks.on_checkpoint)),
      target_paths_(
          settings.shard_samples() > 0 ? uint64_t{settings.shard_samples()} * covered_texels : 0),
      learning_batch_(grow_batches ? learning_batch(covered_texels) : 0) {}

uint64_t BakePolicy::learning_batch(uint64_t covered_texels) {
  return std::max<uint64_t>(uint64_t{1} << 15, 16 * covered_texels);
}

uint64_t BakePolicy::next_batch(uint64_t capacity, uint64_t paths_done) const {
  uint64_t batch = capacity;
  if (learning_batch_ > 0) batch = std::min(batch, std::max(learning_batch_, paths_done));
  if (target_paths_ == 0) return batch;
  return std::min<uint64_t>(batch, target_paths_ - std::min(target_paths_, paths_done));
}

std::optional<Termination> BakePolicy::stop_after_iteration(uint64_t paths_done, double elapsed_s,
                                                            bool cancelled) const {
  if (target_paths_ > 0 && paths_done >= target_paths_) return Termination::kSamples;
  if (cancelled) return Termination::kCancelled;
  if (settings_.time_budget_s > 0 && elapsed_s >= settings_.time_budget_s)
    return Termination::kTime;
  return std::nullopt;
}

bool BakePolicy::report_due(double since_report_s) const {
  return since_report_s >= settings_.progress_interval_s || settings_.target_error > 0;
}

double BakePolicy::tracked_error(const BakeProgress& p) const {
  switch (settings_.target_metric) {
    case ErrorMetric::kRmse:
      return p.rmse;
    case ErrorMetric::kRelMse:
      return p.rel_mse;
    case ErrorMetric::kEstimate:
      break;
  }
  return p.error;
}

bool BakePolicy::error_reached(const BakeProgress& p) const {
  return settings_.target_error > 0 && tracked_error(p) <= settings_.target_error;
}

bool BakePolicy::snapshot_due(double since_snapshot_s) const {
  return snapshots_ && since_snapshot_s >= snapshot_interval_s_;
}

bool BakePolicy::checkpoint_due(double since_checkpoint_s, bool requested) const {
  if (!checkpoints_) return false;
  return (checkpoint_interval_s_ > 0 && since_checkpoint_s >= checkpoint_interval_s_) || requested;
}

void BakePolicy::estimate(BakeProgress& p, bool final_report) const {
  double fraction = 0, eta = -1;
  const double done = static_cast<double>(p.paths);
  const double rate = p.elapsed_s > 0 ? done / p.elapsed_s : 0;
  auto consider = [&](double f, double e) {
    if (f > fraction) fraction = f;
    if (e >= 0 && (eta < 0 || e < eta)) eta = e;
  };
  if (target_paths_ > 0) {
    const double target = static_cast<double>(target_paths_);
    consider(done / target, rate > 0 ? (target - done) / rate : -1);
  }
  if (settings_.time_budget_s > 0)
    consider(p.elapsed_s / settings_.time_budget_s,
             std::max(0.0, settings_.time_budget_s - p.elapsed_s));
  const double tracked = tracked_error(p);
  if (settings_.target_error > 0 && tracked > 0 && p.paths > 0) {
    // The estimate and RMSE fall as 1/sqrt(samples), relMSE as 1/samples:
    // samples needed = now * (err/target)^p.
    const double power = settings_.target_metric == ErrorMetric::kRelMse ? 1.0 : 2.0;
    const double needed = done * std::pow(tracked / settings_.target_error, power);
    consider(std::min(1.0, done / needed), rate > 0 ? std::max(0.0, needed - done) / rate : -1);
  }
  p.fraction = std::min(1.0, final_report ? 1.0 : fraction);
  p.eta_s = final_report ? 0 : eta;
}

}  // namespace luxel::pipeline
