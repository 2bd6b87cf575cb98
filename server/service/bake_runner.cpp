#include "service/bake_runner.h"

#include <chrono>
#include <filesystem>
#include <functional>
#include <optional>

#include "common/clock.h"
#include "job/bake_job.h"
#include "output/reference_exr.h"
#include "service/coordinator/coordinator.h"
#include "service/coordinator/shard_plan.h"
#include "service/files.h"
#include "service/log.h"
#include "service/metrics.h"
#include "settings/fingerprint.h"

namespace luxel::service {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

BakeRunner::BakeRunner(SceneStore& scenes, BakeStore& bakes, JobQueue& queue, RunnerOptions options)
    : scenes_(scenes), bakes_(bakes), queue_(queue), options_(std::move(options)) {}

BakeRunner::~BakeRunner() {
  shutdown();
}

Status BakeRunner::recover() {
  for (const v1::BakeInfo& info : bakes_.list({})) {
    const std::string& id = info.bake_id();
    if (!is_terminal(info.state()) && info.cancel_requested()) {
      // CancelBake was answered before the daemon stopped: the bake ends as
      // asked, not resumed.
      LUXEL_RETURN_IF_ERROR(bakes_.update(
          id,
          [](v1::BakeInfo& b) {
            b.set_state(v1::BAKE_STATE_CANCELLED);
            b.set_termination("cancelled");
            b.set_finished_at(unix_now());
            b.add_notes("cancelled: CancelBake was answered before the daemon stopped");
          },
          /*persist=*/true));
      std::remove(bakes_.checkpoint_path(id).c_str());
      log_event("bake_cancelled", {{"bake", id}, {"scene", info.scene_id()}, {"while", "stopped"}});
      continue;
    }
    if (info.state() == v1::BAKE_STATE_RUNNING) {
      LUXEL_RETURN_IF_ERROR(bakes_.update(
          id,
          [](v1::BakeInfo& b) {
            b.set_state(v1::BAKE_STATE_INTERRUPTED);
            b.add_notes("interrupted: the daemon stopped while the bake ran");
          },
          /*persist=*/true));
      log_event("bake_interrupted", {{"bake", id}, {"scene", info.scene_id()}});
    }
    if (!is_terminal(info.state())) {
      LUXEL_RETURN_IF_ERROR(
          queue_.push(id, info.settings().priority(), bakes_.sequence(id), /*force=*/true));
      log_event("bake_requeued", {{"bake", id}, {"scene", info.scene_id()}});
    }
  }
  return Status::ok();
}

void BakeRunner::start() {
  for (int i = 0; i < std::max(1, options_.max_concurrent_bakes); ++i)
    workers_.emplace_back([this] { worker_loop(); });
}

void BakeRunner::shutdown() {
  if (shutting_down_.exchange(true)) {
    for (auto& w : workers_)
      if (w.joinable()) w.join();
    return;
  }
  queue_.close();
  {
    // Bakes without checkpoints stop at once; the others stop in their next
    // checkpoint hook, right after writing the checkpoint.
    std::lock_guard<std::mutex> lock(mu_);
    if (options_.checkpoint_interval_s <= 0)
      for (auto& [id, r] : running_) r->cancel = true;
  }
  for (auto& w : workers_)
    if (w.joinable()) w.join();
  bakes_.wake_all();
}

Result<v1::BakeInfo> BakeRunner::cancel(const std::string& bake_id, bool finish) {
  std::lock_guard<std::mutex> lock(mu_);
  auto info = bakes_.get(bake_id);
  if (!info) return info.status();
  if (is_terminal(info->state())) return info;
  if (finish) {
    // On disk first: a bake that starts (or restarts) later reads it there.
    LUXEL_RETURN_IF_ERROR(bakes_.update(
        bake_id, [](v1::BakeInfo& b) { b.set_finish_requested(true); }, true));
    if (auto it = running_.find(bake_id); it != running_.end()) it->second->finish = true;
    log_event("bake_finish_requested", {{"bake", bake_id}});
    return bakes_.get(bake_id);
  }
  if (auto it = running_.find(bake_id); it != running_.end()) {
    // On disk first (a restart ends the bake CANCELLED instead of
    // resuming it), then the flag the bake's steps poll; the call does
    // not wait for the bake to stop.
    LUXEL_RETURN_IF_ERROR(bakes_.update(
        bake_id, [](v1::BakeInfo& b) { b.set_cancel_requested(true); }, true));
    it->second->by_user = true;
    it->second->cancel = true;
    log_event("bake_cancel_requested", {{"bake", bake_id}});
    return bakes_.get(bake_id);
  }
  // Queued (or popped by a worker that has not registered it yet: the
  // worker checks the state under mu_ before it starts).
  queue_.remove(bake_id);
  LUXEL_RETURN_IF_ERROR(bakes_.update(
      bake_id,
      [](v1::BakeInfo& b) {
        b.set_state(v1::BAKE_STATE_CANCELLED);
        b.set_termination("cancelled");
        b.set_finished_at(unix_now());
      },
      true));
  log_event("bake_cancelled",
            {{"bake", bake_id}, {"scene", info->scene_id()}, {"while", "queued"}});
  return bakes_.get(bake_id);
}

void BakeRunner::worker_loop() {
  std::unique_ptr<device::Context> ctx;
  while (!shutting_down_) {
    auto id = queue_.pop();
    if (!id) break;
    auto running = std::make_shared<Running>();
    {
      std::lock_guard<std::mutex> lock(mu_);
      auto info = bakes_.get(*id);
      if (!info || is_terminal(info->state())) continue;  // cancelled meanwhile
      running_[*id] = running;
    }
    run_bake(*id, ctx, *running);
    std::lock_guard<std::mutex> lock(mu_);
    running_.erase(*id);
  }
}

void BakeRunner::finish_failed(const std::string& bake_id, const Status& why) {
  log_event("bake_failed", {{"bake", bake_id}, {"error", why.to_string()}});
  // Results half written (a full disk, say) go first: nothing reads them, and
  // the space they free lets the FAILED record below reach the disk.
  remove_tree(bakes_.bake_dir(bake_id) + "/results.partial");
  const Status recorded = bakes_.update(
      bake_id,
      [&](v1::BakeInfo& b) {
        b.set_state(v1::BAKE_STATE_FAILED);
        b.set_error_message(why.to_string());
        b.set_finished_at(unix_now());
      },
      true);
  // Clients already see FAILED; if the record could not say so durably, the
  // next start finds it RUNNING and resumes it (with a note), on purpose.
  if (!recorded.is_ok())
    log_event("record_write_failed", {{"bake", bake_id},
                                      {"state", "BAKE_STATE_FAILED"},
                                      {"error", recorded.to_string()},
                                      {"next_start", "resumes the bake from its checkpoint"}});
}

void BakeRunner::run_bake(const std::string& bake_id, std::unique_ptr<device::Context>& ctx,
                          Running& running) {
  auto info = bakes_.get(bake_id);
  if (!info) return;
  // Validated once, at SubmitBake; here it is only translated.
  std::optional<pipeline::BakeSettings> settings =
      stored_engine_settings(info->settings(), options_.limits);
  const pipeline::JobSettings& opts = settings->job;
  if (const std::string& ref = info->settings().reference_bake_id(); !ref.empty()) {
    // Benchmark mode: the reference bake's irradiance.exr (RGBA).
    auto image = output::read_reference_exr(bakes_.results_dir(ref) + "/irradiance.exr");
    if (!image)
      return finish_failed(
          bake_id, invalid_argument(
                       strprintf("settings.reference_bake_id: cannot use the result of bake %s: %s",
                                 ref.c_str(), image.status().message().c_str())));
    settings->reference = std::make_shared<const std::vector<float>>(std::move(image->pixels));
  }
  auto scene_info = scenes_.get(info->scene_id());
  if (!scene_info) return finish_failed(bake_id, scene_info.status());
  auto scene = scenes_.load_scene(scene_info.value());  // imported once, at upload
  if (!scene) return finish_failed(bake_id, scene.status());
  if (!ctx) {
    auto created = device::Context::create(options_.device_spec);
    if (!created) return finish_failed(bake_id, created.status());
    ctx = std::move(created.value());
  }

  // Resume from the last checkpoint when there is a usable one.
  const std::string fingerprint = pipeline::bake_fingerprint(info->scene_id(), settings.value());
  // After the fingerprint, which keeps "auto": the daemon's choice for it.
  if (settings->intersector == accel::IntersectorKind::kAuto)
    settings->intersector = options_.auto_intersector;
  const std::string ckpt_path = bakes_.checkpoint_path(bake_id);
  std::optional<pipeline::BakeCheckpoint> resume;
  std::string note;
  if (fs::exists(ckpt_path)) {
    auto ckpt = pipeline::read_checkpoint(ckpt_path);
    if (!ckpt) {
      note = "checkpoint unreadable (" + ckpt.status().to_string() + "): restarted from zero";
    } else if (ckpt->fingerprint != fingerprint) {
      note = "checkpoint belongs to other settings: restarted from zero";
    } else {
      resume = std::move(ckpt.value());
      note = strprintf("resumed from checkpoint at %llu paths (iteration %u, %.1f s traced)",
                       static_cast<unsigned long long>(resume->paths_done), resume->iteration,
                       resume->elapsed_s);
    }
    if (!resume) std::remove(ckpt_path.c_str());
  }
  (void)bakes_.update(
      bake_id,
      [&](v1::BakeInfo& b) {
        b.set_state(v1::BAKE_STATE_RUNNING);
        if (b.started_at() == 0) b.set_started_at(unix_now());
        if (resume) b.set_resumed(b.resumed() + 1);
        if (!note.empty()) b.add_notes(note);
      },
      true);
  log_event("bake_started", {{"bake", bake_id},
                             {"scene", info->scene_id()},
                             {"resume", resume ? "yes" : "no"},
                             {"note", note}});

  uint64_t last_paths = resume ? resume->paths_done : 0;
  pipeline::BakeHooks hooks;
  hooks.fingerprint = fingerprint;
  hooks.resume = resume ? &*resume : nullptr;
  hooks.cancel = &running.cancel;
  hooks.discard_cancelled = true;  // a cancelled or interrupted bake's result is not kept
  if (info->finish_requested()) running.finish = true;
  hooks.finish_now = &running.finish;
  hooks.device_turn = &device_turn_;  // concurrent bakes take turns on the one device
  hooks.on_progress = [&](const pipeline::BakeProgress& p) {
    paths_traced_ += p.paths - std::min(p.paths, last_paths);
    last_paths = std::max(last_paths, p.paths);
    (void)bakes_.update(
        bake_id, [&](v1::BakeInfo& b) { *b.mutable_progress() = to_proto(p); }, false);
    if (options_.metrics)
      options_.metrics->bake_progress(bake_id, p.paths, p.elapsed_s, p.device_bytes);
    return true;
  };
  hooks.on_layout = [&](const std::string& line) {
    (void)bakes_.update(
        bake_id, [&](v1::BakeInfo& b) { b.set_lightmap_layout(line); }, false);
  };
  if (opts.snapshot_format != pipeline::SnapshotFormat::kNone) {
    hooks.snapshot_interval_s = opts.snapshot_interval_s;
    hooks.denoise_snapshots = opts.denoise_snapshots;
    hooks.on_snapshot = [&](const pipeline::BakeSnapshot& s) {
      output::Image image{s.width, s.height, 4, s.irradiance};
      bakes_.publish_snapshot(
          bake_id, std::make_shared<SnapshotFrame>(
                       std::move(image), to_proto(s.progress), to_proto(opts.snapshot_format),
                       opts.snapshot_max_side, bakes_.bake_dir(bake_id), s.pages, s.denoised));
    };
  }
  if (options_.checkpoint_interval_s > 0) {
    hooks.checkpoint_interval_s = options_.checkpoint_interval_s;
    hooks.checkpoint_now = &shutting_down_;  // a graceful stop checkpoints at once
    hooks.on_checkpoint = [&](const pipeline::BakeCheckpoint& c) {
      const bool stopping = shutting_down_.load();
      if (Status st = pipeline::write_checkpoint(ckpt_path, c); !st.is_ok()) {
        log_event("checkpoint_failed", {{"bake", bake_id}, {"error", st.to_string()}});
      } else {
        (void)bakes_.update(
            bake_id, [](v1::BakeInfo&) {}, true);  // progress on disk too
        log_event("checkpoint_written",
                  {{"bake", bake_id}, {"paths", std::to_string(c.paths_done)}});
      }
      if (stopping) running.cancel = true;
    };
  }

  // Metrics: every bake that reached the device ends with one observation:
  // before the record's final state where the outcome is known (a client
  // that sees the state finds it counted), else on the way out ("failed").
  std::string outcome = "failed";
  double traced_s = -1;  // the bake's own seconds once known, else wall time
  const auto device_start = Clock::now();
  bool ended = false;
  auto report_end = [&] {
    if (ended || !options_.metrics) return;
    ended = true;
    const double wall = seconds_since(device_start);
    options_.metrics->bake_ended(bake_id, outcome, traced_s >= 0 ? traced_s : wall);
  };
  struct OnExit {
    std::function<void()> f;
    ~OnExit() { f(); }
  } end_on_exit{report_end};
  const bool sharded = options_.coordinator && coordinator::is_sharded(info->settings());
  coordinator::ShardedJob sharded_job{.bake_id = bake_id,
                                      .info = info.value(),
                                      .scene = scene.value().get(),
                                      .scene_main_file = scenes_.main_file_path(scene_info.value()),
                                      .scene_name = scene_info.value().name(),
                                      .settings = &settings.value(),
                                      .ctx = ctx.get(),
                                      .cancel = &running.cancel,
                                      .by_user = &running.by_user,
                                      .finish = &running.finish,
                                      .stopping = &shutting_down_};
  // The job: the lightmap (unless settings.lightmap is off; a sharded one
  // through the coordinator), then the light probes, then the outputs,
  // written into results.partial/ and renamed below.
  job::JobInput input{.scene = scene.value().get(),
                      .settings = settings.value(),
                      .scene_file = scenes_.main_file_path(scene_info.value()),
                      .scene_sha256 = info->scene_id(),
                      .scene_name = scene_info.value().name()};
  job::JobEvents events;
  events.hooks = hooks;
  if (sharded) events.bake_lightmap = [&] { return options_.coordinator->run(sharded_job); };
  events.on_probe_layout = [&](const probes::ProbeLayout&) {
    if (settings->lightmap) last_paths = 0;  // the probe bake counts its paths from zero
  };
  events.on_probes = [&](const probes::ProbeBake& b) {
    log_event("probes_baked", {{"bake", bake_id},
                               {"probes", std::to_string(b.count())},
                               {"inside_flagged", std::to_string(b.layout.flagged_inside)},
                               {"moved", std::to_string(b.layout.moved)},
                               {"paths", std::to_string(b.bake.paths)}});
  };
  const std::string partial = bakes_.bake_dir(bake_id) + "/results.partial";
  const std::string final_dir = bakes_.results_dir(bake_id);
  remove_tree(partial);
  remove_tree(final_dir);
  auto done = job::run_bake_job(input, *ctx, events, partial);
  // A step that polled the cancel request stops with an error of its own
  // (common/cancel.h): with the request set, the job was cancelled, not failed.
  const bool stopped_early = !done && running.cancel.load();
  if (!done && !stopped_early) {
    ctx.reset();  // a driver error may leave the context unusable: the next bake makes a new one
    return finish_failed(bake_id, done.status());
  }
  // The figures of the record: the lightmap's, or the probes' alone.
  const pipeline::BakeResult no_figures;
  const pipeline::BakeResult& r = done ? done->figures() : no_figures;
  // The workers traced a sharded lightmap's paths (and count them themselves).
  if (done && !(sharded && done->lightmap))
    paths_traced_ += r.paths - std::min(r.paths, last_paths);
  if (done) traced_s = r.seconds;

  if (stopped_early || done->cancelled()) {
    remove_tree(partial);
    const bool by_user = running.by_user.load();
    outcome = by_user ? "cancelled" : "interrupted";
    report_end();
    // Logged before the record changes, so whoever sees the new state finds the line.
    log_event(by_user ? "bake_cancelled" : "bake_interrupted",
              {{"bake", bake_id}, {"scene", info->scene_id()}, {"paths", std::to_string(r.paths)}});
    (void)bakes_.update(
        bake_id,
        [&](v1::BakeInfo& b) {
          b.set_state(by_user ? v1::BAKE_STATE_CANCELLED : v1::BAKE_STATE_INTERRUPTED);
          if (by_user) {
            b.set_termination("cancelled");
            b.set_finished_at(unix_now());
          } else {
            b.add_notes("interrupted: the daemon shut down; resumes from its checkpoint");
          }
        },
        true);
    if (by_user) std::remove(ckpt_path.c_str());
    return;
  }

  // Results: the whole folder appears at once (rename), then the record.
  const std::vector<std::string>& written_files = done->written.files;
  if (Status st = fsync_directory(partial); !st.is_ok()) return finish_failed(bake_id, st);
  if (Status st = rename_durable(partial, final_dir); !st.is_ok())
    return finish_failed(bake_id, st);

  outcome = pipeline::termination_name(r.termination);
  report_end();
  log_event("bake_finished", {{"bake", bake_id},
                              {"scene", info->scene_id()},
                              {"termination", pipeline::termination_name(r.termination)},
                              {"seconds", strprintf("%.3f", r.seconds)},
                              {"paths", std::to_string(r.paths)}});
  (void)bakes_.update(
      bake_id,
      [&](v1::BakeInfo& b) {
        b.set_state(v1::BAKE_STATE_SUCCEEDED);
        b.set_finished_at(unix_now());
        b.set_features(r.features);
        b.set_termination(pipeline::termination_name(r.termination));
        b.set_nonfinite_dropped(r.nonfinite_dropped);
        v1::BakeProgress* p = b.mutable_progress();
        p->set_elapsed_s(r.seconds);
        p->set_paths(r.paths);
        p->set_mean_spp(r.mean_spp);
        p->set_min_spp(r.min_spp);
        p->set_error(r.error);
        p->set_eta_s(0);
        p->set_fraction(1);
        b.clear_artifacts();
        for (const std::string& a : written_files) b.add_artifacts(a);
      },
      true);
  // Only once the record says SUCCEEDED: a crash before this line re-runs
  // the bake from the checkpoint rather than from zero.
  std::remove(ckpt_path.c_str());
}

}  // namespace luxel::service
