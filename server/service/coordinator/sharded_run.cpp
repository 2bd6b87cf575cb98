// The coordinator's sharded bake (sharded_run.h): the plan, the combining
// loop (progress, stop rules across shards, merged previews), the merge as a
// fold, and execute() that runs them as named steps.
#include "service/coordinator/sharded_run.h"

#include <algorithm>
#include <chrono>
#include <fstream>
#include <thread>

#include "common/sha256.h"
#include "output/reference_exr.h"
#include "service/files.h"
#include "service/log.h"
#include "service/metrics.h"
#include "settings/fingerprint.h"
#include "shards/checkpoint.h"

namespace luxel::service::coordinator {

v1::BakeProgress Run::publish_progress() {
  std::vector<v1::BakeProgress> parts;
  std::vector<v1::ShardStatus> shards;
  {
    std::lock_guard<std::mutex> lock(mu_);
    shards = status_;
  }
  for (const auto& s : shards) parts.push_back(s.progress());
  const v1::BakeProgress combined = combine_progress(parts);
  (void)bakes_.update(
      job_.bake_id,
      [&](v1::BakeInfo& b) {
        *b.mutable_progress() = combined;
        b.clear_shards();
        for (const auto& s : shards) *b.add_shards() = s;
      },
      false);
  return combined;
}

// Called by the combining loop with the shards' summed progress. Once a rule
// is reached it is recorded (a restarted coordinator keeps it) and every
// shard bake is asked to finish; shards assigned later are asked as soon as
// they are submitted (drive()).
void Run::decide_stop(const v1::BakeProgress& combined) {
  const v1::BakeSettings& s = job_.info.settings();
  std::string rule, why;
  if (job_.finish && job_.finish->load()) {
    rule = "stopped";
    why = "CancelBake asked to finish";
  } else if (s.target_error() > 0 && combined.error() <= s.target_error()) {
    rule = "error";
    why = strprintf("the shards' combined error estimate %.4g reached the target %.4g",
                    combined.error(), s.target_error());
  } else if (s.time_budget_s() > 0 && combined.elapsed_s() >= s.time_budget_s()) {
    rule = "time";
    why = strprintf("the shards traced for %.2f s of the %.2f s budget", combined.elapsed_s(),
                    s.time_budget_s());
  }
  if (rule.empty()) return;
  std::vector<ShardRecord> recs;
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (!plan_.stop.empty()) return;
    plan_.stop = rule;
    if (Status st = persist_locked(); !st.is_ok())
      log_event("coordinator_persist_failed", {{"error", st.to_string()}});
    recs = plan_.shards;
  }
  note(strprintf("stop rule \"%s\": %s; every shard asked to finish with what it traced",
                 rule.c_str(), why.c_str()));
  for (const ShardRecord& r : recs)
    if (!r.downloaded && !r.worker_bake_id.empty())
      ask_to_finish(r.index, r.worker, r.worker_bake_id);
}

// CancelBake with finish on a shard bake, once per bake and process, when a
// stop rule is decided. A failed call is not retried here: the shard's
// watcher calls again after its next re-attach.
void Run::ask_to_finish(uint32_t k, const std::string& worker, const std::string& worker_bake) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (plan_.stop.empty() || finish_sent_.count(worker_bake)) return;
  }
  grpc::Status st = cancel_on(worker, worker_bake, true, 5);
  if (!st.ok()) {
    log_event("shard_finish_failed", {{"bake", job_.bake_id},
                                      {"shard", std::to_string(k)},
                                      {"worker", worker},
                                      {"error", grpc_text(st)}});
    return;
  }
  count("finish_asked");
  std::lock_guard<std::mutex> lock(mu_);
  finish_sent_.insert(worker_bake);
}

// The shards' newest EXR snapshots, averaged per texel weighted by each
// shard's paths: a preview of the merged state, not the merged state (a
// shard's snapshot is its resolved mean; merging means by path counts is
// exact only where every texel got the same share, which uniform sampling
// gives up to one sample). The final result comes from the exact merge.
void Run::publish_snapshot() {
  const auto t0 = SteadyClock::now();
  std::vector<v1::Snapshot> snaps;
  {
    std::lock_guard<std::mutex> lock(mu_);
    snaps = snapshots_;
  }
  output::Image sum;
  double total = 0;
  uint32_t pages = 1;
  std::vector<v1::BakeProgress> parts;
  for (size_t k = 0; k < snaps.size(); ++k) {
    const v1::Snapshot& s = snaps[k];
    parts.push_back(s.progress());
    if (s.data().empty()) continue;
    const std::string scratch = dir_ + strprintf("/snapshot-%zu.exr", k);
    if (!write_file_atomic(scratch, s.data()).is_ok()) continue;
    auto img = output::read_reference_exr(scratch);
    std::remove(scratch.c_str());
    if (!img) continue;
    const double w = double(std::max<uint64_t>(s.progress().paths(), 1));
    if (sum.pixels.empty()) {
      sum = output::Image{img->width, img->height, 4, std::vector<float>(img->pixels.size(), 0.0f)};
      pages = std::max<uint32_t>(1, s.pages());
    }
    if (img->width != sum.width || img->height != sum.height) continue;
    for (size_t i = 0; i < sum.pixels.size(); ++i)
      sum.pixels[i] += static_cast<float>(w * img->pixels[i]);
    total += w;
  }
  if (total <= 0) return;
  for (float& x : sum.pixels) x = static_cast<float>(x / total);
  const v1::BakeSettings& s = job_.info.settings();
  const int max_side = s.snapshot_max_side() ? int(s.snapshot_max_side()) : 512;
  bakes_.publish_snapshot(
      job_.bake_id,
      std::make_shared<SnapshotFrame>(std::move(sum), combine_progress(parts), s.snapshot_format(),
                                      max_side, bakes_.bake_dir(job_.bake_id), int(pages), false));
  ++previews_;
  preview_s_ += seconds_since(t0);
}

grpc::Status Run::cancel_on(const std::string& worker, const std::string& worker_bake, bool finish,
                            double deadline_s) {
  grpc::ClientContext ctx;
  pool_.prepare(ctx, deadline_s);
  v1::CancelBakeRequest req;
  req.set_bake_id(worker_bake);
  req.set_finish(finish);
  v1::BakeInfo info;
  return pool_.stub(worker)->CancelBake(&ctx, req, &info);
}

void Run::cancel_workers() {
  std::vector<ShardRecord> recs;
  {
    std::lock_guard<std::mutex> lock(mu_);
    recs = plan_.shards;
  }
  for (const ShardRecord& r : recs) {
    if (r.downloaded || r.worker_bake_id.empty()) continue;
    (void)cancel_on(r.worker, r.worker_bake_id, false, 2);
  }
}

// Best effort, from the combining loop and at the end: a reassigned shard's
// old bake would otherwise run to its end on a worker that comes back (a
// restarted luxeld resumes its bakes), taking the worker from other shards.
void Run::cancel_abandoned() {
  std::vector<std::pair<std::string, std::string>> todo;
  {
    std::lock_guard<std::mutex> lock(mu_);
    todo = plan_.abandoned;
  }
  if (todo.empty()) return;
  std::vector<std::pair<std::string, std::string>> done;
  for (const auto& [worker, bake] : todo) {
    grpc::Status st = cancel_on(worker, bake, false, 1);
    if (st.ok() || st.error_code() == grpc::StatusCode::NOT_FOUND) {
      done.emplace_back(worker, bake);
      log_event("abandoned_shard_cancelled",
                {{"bake", job_.bake_id}, {"worker", worker}, {"worker_bake", bake}});
    }
  }
  std::lock_guard<std::mutex> lock(mu_);
  for (const auto& d : done)
    plan_.abandoned.erase(std::remove(plan_.abandoned.begin(), plan_.abandoned.end(), d),
                          plan_.abandoned.end());
  if (!done.empty()) (void)persist_locked();
}

// Folds every downloaded shard whose predecessors are folded: the merge
// overlaps the downloads of later shards and holds one shard's state at a
// time (not all of them).
Status Run::fold_downloaded() {
  for (;;) {
    const uint32_t k = merger_.added();
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (k >= plan_.count || !plan_.shards[k].downloaded) return Status::ok();
    }
    const auto t0 = SteadyClock::now();
    auto c = pipeline::read_checkpoint(shard_path(k));
    if (!c)
      return Status(c.status().code(), strprintf("shard %u: %s", k, c.status().message().c_str()));
    fold_read_s_ += seconds_since(t0);
    const auto t1 = SteadyClock::now();
    LUXEL_RETURN_IF_ERROR(merger_.add(c.value()));
    fold_merge_s_ += seconds_since(t1);
  }
}

Result<pipeline::BakeResult> Run::merge() {
  LUXEL_RETURN_IF_ERROR(fold_downloaded());
  auto merged = merger_.finish();
  if (!merged) return merged.status();
  const auto t2 = SteadyClock::now();
  pipeline::BakeHooks hooks;
  hooks.on_layout = [&](const std::string& line) {
    (void)bakes_.update(
        job_.bake_id, [&](v1::BakeInfo& b) { b.set_lightmap_layout(line); }, false);
  };
  const pipeline::Termination why = merged_termination(plan_);
  auto result = pipeline::finish_merged_bake(*job_.scene, *job_.settings, *job_.ctx, merged.value(),
                                             why, hooks);
  if (result && why != pipeline::Termination::kSamples)
    note(strprintf(
        "merged %llu paths of the shards (ended on %s): mean %.1f samples per texel, "
        "minimum %u, error estimate %.4g",
        static_cast<unsigned long long>(result.value().paths), pipeline::termination_name(why),
        result.value().mean_spp, result.value().min_spp, result.value().error));
  log_event("shards_merged", {{"bake", job_.bake_id},
                              {"shards", std::to_string(plan_.count)},
                              {"read_s", strprintf("%.4f", fold_read_s_)},
                              {"merge_s", strprintf("%.4f", fold_merge_s_)},
                              {"finish_s", strprintf("%.4f", seconds_since(t2))}});
  if (options_.metrics)
    options_.metrics->shards_merged(fold_read_s_, fold_merge_s_, seconds_since(t2));
  return result;
}
Result<pipeline::BakeResult> Run::execute() {
  dir_ = bakes_.bake_dir(job_.bake_id) + "/shards";
  LUXEL_RETURN_IF_ERROR(make_directories(dir_));
  if (auto st = cli::remote::collect_scene_files(job_.scene_main_file, scene_files_); !st.ok())
    return Status(StatusCode::kInternal, "scene files for the workers: " + st.error_message());
  // The plan: the one on disk (a restarted coordinator), else a new one.
  const std::string plan_file = bakes_.bake_dir(job_.bake_id) + "/shards.json";
  bool resumed = false;
  if (fs::exists(plan_file)) {
    auto text = read_whole_file(plan_file);
    auto plan = text ? plan_from_json(text.value()) : Result<ShardPlan>(text.status());
    if (plan) {
      plan_ = std::move(plan.value());
      resumed = true;
    } else {
      note("coordinator state unreadable (" + plan.status().to_string() + "): sharded anew");
    }
  }
  LUXEL_RETURN_IF_ERROR(resumed ? resume_plan() : plan_shards());
  start_status();
  const v1::BakeSettings& s = job_.info.settings();
  stop_rules_ = s.time_budget_s() > 0 || s.target_error() > 0;
  std::vector<std::thread> threads;
  for (uint32_t k = 0; k < plan_.count; ++k) threads.emplace_back([this, k] { drive(k); });
  const bool all_done = combine_until_done();
  for (auto& t : threads) t.join();
  return conclude(all_done);
}

Status Run::plan_shards() {
  const v1::BakeSettings& s = job_.info.settings();
  uint32_t count = s.shards();
  if (s.shards_auto()) {
    const auto t0 = SteadyClock::now();
    std::vector<std::string> workers;
    while ((workers = pool_.resolve()).empty() && seconds_since(t0) < options_.grace_s &&
           !job_.cancel->load())
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
    if (workers.empty())
      return Status(
          StatusCode::kUnavailable,
          strprintf("settings.shards_auto: no worker resolved within %.0f s", options_.grace_s));
    // At least two: one worker then runs both in turn (a shard bake of
    // shard_count 1 would be a whole bake, without accumulators.bin).
    count = usable_shard_count(s, std::max<uint32_t>(2, uint32_t(workers.size())), options_.limits);
    if (count < 2)
      return invalid_argument("settings.samples_per_texel: too few samples to split into 2 shards");
  }
  count = std::max<uint32_t>(count, 1);
  remove_tree(dir_);
  LUXEL_RETURN_IF_ERROR(make_directories(dir_));
  plan_.count = count;
  plan_.shards.resize(count);
  for (uint32_t k = 0; k < count; ++k) plan_.shards[k].index = k;
  LUXEL_RETURN_IF_ERROR(persist_locked());
  note(strprintf("sharded into %u shards across the workers", count));
  return Status::ok();
}

Status Run::resume_plan() {
  uint32_t attached = 0, done = 0;
  for (const ShardRecord& r : plan_.shards) {
    if (r.downloaded && !fs::exists(shard_path(r.index))) {
      // Lost from disk (a wiped folder): the shard runs again.
      plan_.shards[r.index] = ShardRecord{.index = r.index, .attempts = r.attempts};
      continue;
    }
    done += r.downloaded;
    attached += !r.downloaded && !r.worker_bake_id.empty();
  }
  LUXEL_RETURN_IF_ERROR(persist_locked());
  note(strprintf("coordinator restarted: %u of %u shards downloaded, re-attaching to %u", done,
                 plan_.count, attached));
  return Status::ok();
}

void Run::start_status() {
  // Every shard's accumulators carry this; shard_index/shard_count are left
  // out of it by the engine, so shard 0's settings stand for all.
  fingerprint_ = pipeline::bake_fingerprint(
      job_.info.scene_id(),
      stored_engine_settings(shard_settings(job_.info.settings(), 0, plan_.count),
                             options_.limits));
  status_.resize(plan_.count);
  snapshots_.resize(plan_.count);
  for (uint32_t k = 0; k < plan_.count; ++k) {
    const ShardRecord& r = plan_.shards[k];
    status_[k].set_index(k);
    status_[k].set_worker(r.worker);
    status_[k].set_worker_bake_id(r.worker_bake_id);
    status_[k].set_attempts(r.attempts);
    status_[k].set_state(r.downloaded               ? v1::SHARD_STATE_DOWNLOADED
                         : r.worker_bake_id.empty() ? v1::SHARD_STATE_PENDING
                                                    : v1::SHARD_STATE_RUNNING);
  }
}

bool Run::combine_until_done() {
  const v1::BakeSettings& s = job_.info.settings();
  const double progress_every =
      s.progress_interval_s() > 0 ? std::max(0.05, s.progress_interval_s()) : 1.0;
  const double snapshot_every =
      s.snapshot_interval_s() > 0 ? std::max(0.05, s.snapshot_interval_s()) : 5.0;
  auto last_progress = SteadyClock::now(), last_snapshot = SteadyClock::now(),
       last_cleanup = SteadyClock::now();
  uint64_t snapshots_seen = 0;
  bool all_done = false;
  while (!all_done) {
    {
      std::unique_lock<std::mutex> lock(mu_);
      wake_.wait_for(lock, std::chrono::milliseconds(100));
      all_done = std::all_of(plan_.shards.begin(), plan_.shards.end(),
                             [](const ShardRecord& r) { return r.downloaded; });
      if (failure_) break;
    }
    if (host_stopped()) break;
    if (Status st = fold_downloaded(); !st.is_ok()) {
      // A checked download that does not read back: the disk under the
      // data dir failed. The bake fails rather than merge less.
      fail(st);
      break;
    }
    if (seconds_since(last_cleanup) >= 1) {
      cancel_abandoned();
      last_cleanup = SteadyClock::now();
    }
    check_stop_rules(all_done, progress_every, last_progress);
    maybe_publish_snapshot(snapshot_every, last_snapshot, snapshots_seen);
  }
  return all_done;
}

bool Run::host_stopped() {
  if (!job_.cancel->load() && !(job_.stopping && job_.stopping->load())) return false;
  std::lock_guard<std::mutex> lock(mu_);
  stop_ = true;
  for (auto& [k, ctx] : active_) ctx->TryCancel();
  wake_.notify_all();
  return true;
}

// Progress every progress_every seconds (and once every shard is in), with
// the stop rules decided on it; between reports too while a rule waits.
void Run::check_stop_rules(bool all_done, double progress_every, SteadyClock::time_point& last) {
  if (seconds_since(last) >= progress_every || all_done) {
    const v1::BakeProgress combined = publish_progress();
    if (!all_done) decide_stop(combined);
    last = SteadyClock::now();
  } else if (stop_rules_ || (job_.finish && job_.finish->load())) {
    // Between published reports too: the shards trace on while the rule waits.
    std::vector<v1::BakeProgress> parts;
    {
      std::lock_guard<std::mutex> lock(mu_);
      for (const auto& st : status_) parts.push_back(st.progress());
    }
    decide_stop(combine_progress(parts));
  }
}

void Run::maybe_publish_snapshot(double every, SteadyClock::time_point& last, uint64_t& seen) {
  if (job_.info.settings().snapshot_format() == v1::SNAPSHOT_FORMAT_NONE ||
      seconds_since(last) < every)
    return;
  uint64_t changes;
  {
    std::lock_guard<std::mutex> lock(mu_);
    changes = snapshot_changes_;
  }
  if (changes != seen) {
    publish_snapshot();
    seen = changes;
  }
  last = SteadyClock::now();
}

Result<pipeline::BakeResult> Run::conclude(bool all_done) {
  publish_progress();
  cancel_abandoned();
  log_event(
      "shards_watched",
      {{"bake", job_.bake_id},
       {"previews", std::to_string(previews_)},
       {"preview_ms_mean", strprintf("%.2f", previews_ ? 1e3 * preview_s_ / previews_ : 0.0)}});
  if (failure_) {
    cancel_workers();
    return failure_.value();
  }
  if (!all_done) {
    // CancelBake cancels the shard bakes; a daemon shutdown leaves them
    // running for the next start to re-attach to.
    if (job_.by_user && job_.by_user->load()) cancel_workers();
    pipeline::BakeResult r;
    r.termination = pipeline::Termination::kCancelled;
    return r;
  }
  return merge();
}

}  // namespace luxel::service::coordinator
