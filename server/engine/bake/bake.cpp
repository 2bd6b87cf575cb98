// A bake as named steps (baker.h has the Baker; Cycles' RenderScheduler and
// PathTrace::render_pipeline are the model): the policy (bake_policy.h)
// says what is due after each iteration, and run_tile calls one step per
// action. The stages of an iteration are in baker_iteration.cpp, setup and
// tiles in baker_tiles.cpp, the denoiser in baker_denoise.cpp.
#include "bake/bake.h"

#include <algorithm>
#include <memory>
#include <mutex>

#include "bake/baker.h"
#include "bake/host_memory.h"

namespace luxel::pipeline {

// Setup, then the resumed state or the first tile on the device.
Result<size_t> Baker::start() {
  const BakeHooks& hooks = *hooks_;
  const auto t_setup = SteadyClock::now();
  ctx_.timer().reset();
  LUXEL_RETURN_IF_ERROR(setup());
  // Shards keep every tile's state for BakeResult::final_state.
  keep_finished_ = (tiled() && static_cast<bool>(hooks.on_checkpoint)) || settings_.sharded() ||
                   hooks.keep_final_state;
  LUXEL_RETURN_IF_ERROR(begin_result(s_, result_, CancelToken(hooks.cancel)));
  size_t first_tile = 0;
  if (hooks.resume) {
    if (hooks.resume->fingerprint != hooks.fingerprint)
      return invalid_argument("checkpoint belongs to another scene or other settings");
    // Shards of one bake share the fingerprint, not their samples.
    const uint32_t index = settings_.sharded() ? settings_.shard_index : 0;
    const uint32_t count = settings_.sharded() ? settings_.shard_count : 1;
    if (hooks.resume->shard_index != index || hooks.resume->shard_count != count)
      return invalid_argument(strprintf("checkpoint is shard %u of %u, this bake shard %u of %u",
                                        hooks.resume->shard_index, hooks.resume->shard_count, index,
                                        count));
    auto tile = resume_tiles(*hooks.resume, result_);
    if (!tile) return tile.status();
    first_tile = tile.value();
    if (!whole_state_) paths_done_ = hooks.resume->paths_done;
    resumed_elapsed_ = hooks.resume->elapsed_s;
    progress_.iteration = hooks.resume->iteration;
    result_.series = series_from_checkpoint(*hooks.resume);
  } else {
    LUXEL_RETURN_IF_ERROR(b_.load_tile(ctx_, s_, plan_.tiles[0].begin, plan_.tiles[0].end,
                                       CancelToken(hooks.cancel)));
  }
  LUXEL_RETURN_IF_ERROR(ctx_.finish());
  LUXEL_RETURN_IF_ERROR(check_cancel(CancelToken(hooks.cancel), "the first tile's clear"));
  result_.setup_s = seconds_since(t_setup);
  return first_tile;
}

// A cancelled bake whose host throws it away (BakeHooks::discard_cancelled):
// the figures of the log only.
BakeResult Baker::discarded() {
  result_.termination = Termination::kCancelled;
  result_.seconds = elapsed();
  result_.paths = done_.paths + paths_done_;
  return std::move(result_);
}

Result<BakeResult> Baker::run(const BakeHooks& hooks) {
  LUXEL_RETURN_IF_ERROR(validate_settings(settings_));
  hooks_ = &hooks;
  auto first_tile = start();
  if (!first_tile) return first_tile.status();
  const BakePolicy policy(settings_, hooks, s_.params.covered_count);
  policy_ = &policy;
  t_start_ = SteadyClock::now();
  last_report_ = last_snapshot_ = last_checkpoint_ = SteadyClock::now();

  Termination why = Termination::kSamples;
  for (size_t ti = first_tile.value(); ti < plan_.tiles.size(); ++ti) {
    auto stopped = run_tile(ti, ti > first_tile.value());
    if (!stopped) return stopped.status();
    why = stopped.value();
    if (why == Termination::kCancelled && hooks.discard_cancelled) return discarded();
    const bool last = ti + 1 == plan_.tiles.size() || why == Termination::kCancelled;
    LUXEL_RETURN_IF_ERROR(finish_tile(plan_.tiles[ti], last));
    if (last) break;
  }
  if ((settings_.sharded() || hooks.keep_final_state) && why != Termination::kCancelled)
    keep_final_state();
  // A cancel that came after the last iteration: the solve and the denoise
  // take seconds at 2048^2 with directional encodings.
  if (hooks.discard_cancelled && cancelled()) return discarded();
  finish_result(s_, settings_, result_);
  if (hooks.discard_cancelled && cancelled()) return discarded();
  // Device memory of the bake (with a snapshot denoiser, held beside it).
  size_t peak = device_bytes_held() + (denoiser_ ? denoiser_->device_bytes() : 0);
  if (denoise_method() != Denoise::kOff) {
    auto held = denoise_result();
    if (!held) return held.status();
    peak = std::max(peak, held.value());
  } else if (settings_.denoise == Denoise::kAuto) {
    result_.denoise_json = auto_off_json();
  }
  record_final_progress(progress_, ctx_, result_);
  result_.termination = why;
  result_.tiles = plan_.tiles.size();
  result_.batch_paths = s_.capacity;
  result_.device_memory_budget = budget_;
  result_.peak_device_bytes = peak;
  return std::move(result_);
}

// Iterations of tile `ti` until one of its stopping rules (tile_plan.h: its
// texels' samples, its share of the time budget, the target error on its
// texels) or the host ends it; after each, what the policy says is due.
Result<Termination> Baker::run_tile(size_t ti, bool load) {
  const BakeHooks& hooks = *hooks_;
  const Tile& tile = plan_.tiles[ti];
  BakeSettings tile_settings = settings_;
  if (tiled() && settings_.time_budget_s > 0)
    tile_settings.time_budget_s = settings_.time_budget_s * static_cast<double>(tile.end) /
                                  static_cast<double>(s_.info.covered_texels.size());
  const BakePolicy tile_policy(tile_settings, hooks, tile.end - tile.begin, s_.grow_batches);
  progressive_.reset();
  if (load) {
    LUXEL_RETURN_IF_ERROR(b_.load_tile(ctx_, s_, tile.begin, tile.end));
    paths_done_ = 0;
    if (whole_state_) LUXEL_RETURN_IF_ERROR(restore_whole_state(tile.begin, tile.end));
  }
  for (;;) {
    if (hooks.finish_now && hooks.finish_now->load()) return Termination::kStopped;
    const uint64_t batch = tile_policy.next_batch(s_.capacity, paths_done_);
    // Resumed with the samples already traced (a merge of shards): the
    // outputs come from the restored state, no iteration runs.
    if (batch == 0) return Termination::kSamples;
    auto ran = iterate(batch);
    if (!ran) return ran.status();
    const bool completed = ran.value();
    // Given up mid-iteration: cancelled, or a checkpoint first (then the
    // same iteration runs again: same first path, same bits).
    if (!completed && cancelled()) return Termination::kCancelled;
    if (completed) ++progress_.iteration;
    if (auto stop = tile_policy.stop_after_iteration(paths_done_, elapsed(), cancelled()))
      return *stop;
    if (completed && tracks_progressive_variance()) LUXEL_RETURN_IF_ERROR(record_milestone(tile));
    if (policy_->report_due(seconds_since(last_report_))) {
      auto keep_going = report(false);
      if (!keep_going) return keep_going.status();
      if (tile_policy.error_reached(tile_progress_)) return Termination::kError;
      if (!keep_going.value()) return Termination::kCancelled;
    }
    if (policy_->snapshot_due(seconds_since(last_snapshot_)))
      LUXEL_RETURN_IF_ERROR(send_snapshot(tile));
    const bool requested = hooks.checkpoint_now && hooks.checkpoint_now->load();
    if (policy_->checkpoint_due(seconds_since(last_checkpoint_), requested)) {
      LUXEL_RETURN_IF_ERROR(write_checkpoint(ti));
      // A host that checkpoints to stop (daemon shutdown) cancels in the
      // hook: stop here rather than trace an iteration the checkpoint lacks.
      if (cancelled()) return Termination::kCancelled;
    }
  }
}

Result<bool> Baker::iterate(uint64_t batch) {
  std::unique_lock<std::mutex> turn;
  if (hooks_->device_turn) turn = std::unique_lock<std::mutex>(*hooks_->device_turn);
  auto ran = run_iteration(static_cast<uint32_t>(batch));
  if (!ran) return ran.status();
  LUXEL_RETURN_IF_ERROR(ctx_.finish());
  return ran.value();
}

// Statistics, then the progress callback; false: the host cancels.
Result<bool> Baker::report(bool final_report) {
  LUXEL_RETURN_IF_ERROR(compute_stats(tile_progress_));
  const uint32_t iteration = progress_.iteration;
  progress_ = globalize(tile_progress_);
  progress_.iteration = iteration;
  progress_.elapsed_s = elapsed();
  progress_.device_bytes = device_bytes_held();
  policy_->estimate(progress_, final_report);
  // The final report after a stopping rule repeats the last point: replace it.
  std::vector<ErrorSample>& series = result_.series;
  if (!series.empty() && series.back().paths == progress_.paths) series.pop_back();
  series.push_back({progress_.elapsed_s, progress_.paths, progress_.mean_spp, progress_.min_spp,
                    progress_.error, progress_.rmse, progress_.rel_mse});
  last_report_ = SteadyClock::now();
  return !hooks_->on_progress || hooks_->on_progress(progress_);
}

// A milestone of the denoiser's variance estimate when the tile's mean count
// has doubled (bake/progressive_variance.h).
Status Baker::record_milestone(const Tile& tile) {
  const double mean_spp =
      static_cast<double>(paths_done_) / static_cast<double>(tile.end - tile.begin);
  if (!progressive_.due(mean_spp)) return Status::ok();
  auto state = read_state();
  if (!state) return state.status();
  progressive_.record(state.value(), mean_spp);
  return Status::ok();
}

Status Baker::send_snapshot(const Tile& tile) {
  auto state = read_state();
  if (!state) return state.status();
  BakeSnapshot snap;
  snap.width = s_.atlas.width;
  snap.height = s_.atlas.height;
  snap.pages = s_.atlas.pages;
  snap.irradiance = result_.irradiance;  // the finished tiles (zero untiled)
  fill_irradiance(s_, state.value().mean, tile.begin, snap.irradiance);
  if (hooks_->denoise_snapshots && denoise_method() != Denoise::kOff) {
    std::vector<float> rel_error = result_.rel_error;
    fill_rel_error(s_, state.value(), tile.begin, rel_error);
    size_t two_point = 0;
    const std::vector<float> variance =
        atlas_variance(snap.irradiance, rel_error, &state.value(), tile.begin, &two_point);
    std::unique_lock<std::mutex> turn;
    if (hooks_->device_turn) turn = std::unique_lock<std::mutex>(*hooks_->device_turn);
    auto filtered = denoise(snap.irradiance, variance, two_point);
    if (!filtered) return filtered.status();
    snap.irradiance = std::move(filtered.value());
    snap.denoised = true;
  }
  // The image's own statistics (error, min spp), not those of the last
  // progress report.
  LUXEL_RETURN_IF_ERROR(compute_stats(tile_progress_));
  snap.progress = globalize(tile_progress_);
  snap.progress.iteration = progress_.iteration;
  snap.progress.elapsed_s = elapsed();
  hooks_->on_snapshot(snap);
  last_snapshot_ = SteadyClock::now();
  return Status::ok();
}

Status Baker::write_checkpoint(size_t ti) {
  auto state = read_state();
  if (!state) return state.status();
  if (tiled()) state.value() = tiled_checkpoint(state.value(), ti);
  BakeCheckpoint& c = state.value();
  c.fingerprint = hooks_->fingerprint;
  c.iteration = progress_.iteration;
  c.elapsed_s = elapsed();
  series_to_checkpoint(result_.series, c);
  hooks_->on_checkpoint(c);
  if (tiled()) return_finished(c);
  last_checkpoint_ = SteadyClock::now();
  return Status::ok();
}

// The tile's state into the result; its statistics into done_. The last
// tile (or a cancelled one) ends with the final report.
Status Baker::finish_tile(const Tile& tile, bool last) {
  // A host that throws a cancelled bake away (the daemon) stops here too:
  // the read-back and its assembly take a second at 2048^2.
  const CancelToken cancel(hooks_->discard_cancelled ? hooks_->cancel : nullptr);
  if (last) {
    result_.seconds = elapsed();
    auto final_report = report(true);
    if (!final_report) return final_report.status();
  } else {
    LUXEL_RETURN_IF_ERROR(compute_stats(tile_progress_));
  }
  LUXEL_RETURN_IF_ERROR(check_cancel(cancel, "the tile's read-back"));
  uint64_t nonfinite = 0;
  if (!keep_finished_ && !tracks_progressive_variance()) {
    // Into the result a slice at a time: the host holds a slice of the
    // tile's state beside the result images, not a copy of the whole tile.
    const size_t slots = tile.end - tile.begin;
    for (size_t first = 0; first < slots; first += kStateSliceSlots) {
      BakeCheckpoint part;
      LUXEL_RETURN_IF_ERROR(
          b_.read_state(ctx_, part, first, std::min(kStateSliceSlots, slots - first), cancel));
      LUXEL_RETURN_IF_ERROR(check_cancel(cancel, "the tile's read-back"));
      if (first == 0) nonfinite = part.nonfinite;
      part.nonfinite = 0;
      write_state(s_, part, tile.begin + first, result_);
    }
    result_.nonfinite_dropped += nonfinite;
  } else {
    auto state = read_state(cancel);
    if (!state) return state.status();
    LUXEL_RETURN_IF_ERROR(check_cancel(cancel, "the tile's read-back"));
    write_state(s_, state.value(), tile.begin, result_);
    if (tracks_progressive_variance())
      two_point_texels_ += progressive_.fill(s_, state.value(), tile.begin, denoise_variance_);
    if (keep_finished_) append_state(finished_, state.value());
    nonfinite = state.value().nonfinite;
  }
  const double n = static_cast<double>(tile.end - tile.begin);
  done_.slots = tile.end;
  done_.paths += paths_done_;
  done_.nonfinite += nonfinite;
  // Weighted by coverage as the error is (globalize); only tiled bakes read it.
  if (tiled())
    done_.error_sum +=
        tile_progress_.error * (coverage_before(tile.end) - coverage_before(tile.begin));
  if (settings_.reference) {
    done_.sq_sum += tile_progress_.rmse * tile_progress_.rmse * n;
    done_.rel_sum += tile_progress_.rel_mse * n;
  }
  done_.min_spp = std::min(done_.min_spp, tile_progress_.min_spp);
  return Status::ok();
}

// BakeResult::final_state: every tile's accumulators (a shard's, or a whole
// bake's as one shard of itself).
void Baker::keep_final_state() {
  auto state = std::make_shared<BakeCheckpoint>();
  BakeCheckpoint& f = *state;
  append_state(f, finished_);
  f.fingerprint = hooks_->fingerprint;
  label_state(f);
  f.width = static_cast<uint32_t>(s_.atlas.width);
  f.height = static_cast<uint32_t>(s_.atlas.height);
  f.paths_done = done_.paths;
  f.iteration = progress_.iteration;
  f.elapsed_s = result_.seconds;
  f.nonfinite = done_.nonfinite;
  series_to_checkpoint(result_.series, f);
  result_.final_state = std::move(state);
}

Result<BakeResult> bake(const scene::Scene& scene, const BakeSettings& settings,
                        device::Context& ctx, const BakeHooks& hooks) {
  const auto t0 = SteadyClock::now();
  const CancelToken cancel(hooks.cancel);
  auto layout = lay_out_lightmap(scene, settings, cancel);
  if (!layout) return layout.status();
  LUXEL_RETURN_IF_ERROR(check_cancel(cancel, "the lightmap layout"));
  const double layout_s = seconds_since(t0);
  if (hooks.on_layout)
    hooks.on_layout(describe_lightmap_layout(layout.value()) +
                    describe_layout_warnings(layout.value().atlas));
  Baker baker(layout.value(), settings, ctx);
  auto result = baker.run(hooks);
  if (!result) return result;
  result.value().uv_layout = layout.value().generated;
  if (settings.seam_stitch) {
    const auto t_seams = SteadyClock::now();
    result.value().seams = std::make_shared<const atlas::SeamSet>(
        atlas::find_seams(*layout.value().scene, result.value().atlas));
    result.value().seam_find_s = seconds_since(t_seams);
  }
  result.value().setup_s += layout_s;
  return result;
}

Result<BakeResult> bake_probe_domain(const scene::Scene& scene, const BakeSettings& settings,
                                     const ProbeDomain& probes, device::Context& ctx,
                                     const BakeHooks& hooks) {
  if (probes.max_distance.size() != probes.positions.size())
    return invalid_argument("probe domain: one visibility cap per probe");
  // Texel-space features have no meaning for points in free space.
  if (settings.filter == Filter::kGaussian)
    return invalid_argument("settings.filter: probes take the box filter only");
  if (settings.adaptive) return invalid_argument("settings.adaptive: not supported for probes");
  LightmapLayout layout;
  layout.scene = &scene;
  Baker baker(layout, settings, ctx, &probes);
  return baker.run(hooks);
}

Result<BakeResult> bake(const scene::Scene& scene, const BakeSettings& settings,
                        device::Context& ctx, const ProgressFn& on_progress) {
  BakeHooks hooks;
  hooks.on_progress = on_progress;
  return bake(scene, settings, ctx, hooks);
}

}  // namespace luxel::pipeline
