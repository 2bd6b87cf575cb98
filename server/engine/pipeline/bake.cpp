// The iteration scheduler of a bake: prepares the scene (bake_setup), owns
// the device buffers (bake_buffers) and kernels (bake_kernels), runs the
// wavefront stages of one iteration in order, and asks the policy
// (bake_policy) when to report, snapshot, checkpoint and stop; the result is
// put together by bake_assembly.
#include "pipeline/bake.h"

#include <chrono>
#include <cmath>

#include "pipeline/bake_assembly.h"
#include "pipeline/bake_buffers.h"
#include "pipeline/bake_kernels.h"
#include "pipeline/bake_policy.h"
#include "pipeline/bake_setup.h"
#include "pipeline/primitives/offset_buffer.h"
#include "pipeline/primitives/radix_sort.h"
#include "pipeline/primitives/stream_compaction.h"

namespace luxel::pipeline {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

class Baker {
 public:
  Baker(const scene::Scene& scene, const BakeSettings& settings, device::Context& ctx)
      : scene_(scene), settings_(settings), ctx_(ctx) {}

  Result<BakeResult> run(const BakeHooks& hooks);

 private:
  Status setup();
  Status launch(BakeKernel k, size_t global, size_t local = 64) {
    LUXEL_RETURN_IF_ERROR(kernels_.bind(k, b_.args()));
    return ctx_.launch(kernels_[k], global, local);
  }
  Status run_iteration(uint32_t batch);
  Status trace_shadows(bool texel_point);
  Status compute_stats(BakeProgress& p);
  Result<BakeCheckpoint> read_state() {
    BakeCheckpoint c;
    LUXEL_RETURN_IF_ERROR(b_.read_state(ctx_, c));
    c.paths_done = paths_done_;
    return c;
  }

  const scene::Scene& scene_;
  const BakeSettings& settings_;
  device::Context& ctx_;

  BakeSetup s_;
  BakeBuffers b_;
  BakeKernels kernels_;
  std::unique_ptr<RadixSort> sort_;
  std::unique_ptr<StreamCompaction> compaction_;  // null with compaction off
  std::unique_ptr<OffsetBuffer> offset_buffer_;
  uint64_t paths_done_ = 0;
};

Status Baker::setup() {
  auto setup = prepare_bake(scene_, settings_, ctx_);
  if (!setup) return setup.status();
  s_ = std::move(setup.value());
  auto buffers = BakeBuffers::create(ctx_, scene_, s_, settings_);
  if (!buffers) return buffers.status();
  b_ = std::move(buffers.value());
  auto sort = RadixSort::create(ctx_, s_.capacity);
  if (!sort) return sort.status();
  sort_ = std::move(sort.value());
  if (settings_.compaction) {
    auto compaction = StreamCompaction::create(ctx_, s_.capacity);
    if (!compaction) return compaction.status();
    compaction_ = std::move(compaction.value());
  }
  auto offsets = OffsetBuffer::create(ctx_, s_.capacity, s_.params.covered_count);
  if (!offsets) return offsets.status();
  offset_buffer_ = std::move(offsets.value());
  auto kernels = BakeKernels::create(ctx_, s_.features);
  if (!kernels) return kernels.status();
  kernels_ = std::move(kernels.value());
  return Status::ok();
}

// Any-hit queries for the active list's shadow rays, then their results: into
// the paths' radiance, or (texel point with directional encodings) into the
// basis samples, which keep the light sample apart from the first segment.
Status Baker::trace_shadows(bool texel_point) {
  const LiveArgs& live = b_.args().live;
  const PathArgs& g = b_.args().paths;
  LUXEL_RETURN_IF_ERROR(s_.tracer->any_indexed(g.shadow_rays, *live.active, *live.count, kSlotMask,
                                               g.occluded, s_.capacity));
  return launch(texel_point ? BakeKernel::resolve_texel_shadows : BakeKernel::resolve_shadows,
                s_.capacity);
}

// One iteration of the wavefront pipeline (module comment of kernels/bake.cl).
Status Baker::run_iteration(uint32_t batch) {
  BakeArgs& a = b_.args();
  const size_t cap = s_.capacity;
  const bool nee = s_.features.has("NEE");
  const bool sort_directions = settings_.sort_directions;
  a.params.paths = batch;
  a.params.first_path = paths_done_;

  // 1. Texel domain, 2. radix sort by texel (keys are covered slots, which
  // ascend with texels; only the bits the slot range needs), 3. offset
  // buffer over slots (Listing 3.1).
  LUXEL_RETURN_IF_ERROR(launch(BakeKernel::texel_domain, cap));
  const int32_t count = static_cast<int32_t>(batch);
  LUXEL_RETURN_IF_ERROR(ctx_.write(b_.batch_count, &count, sizeof count));
  LUXEL_RETURN_IF_ERROR(sort_->enqueue(a.paths.keys, device::Buffer(), b_.batch_count, cap, 0,
                                       RadixSort::bits_for(a.params.covered_count - 1)));
  LUXEL_RETURN_IF_ERROR(
      offset_buffer_->enqueue(a.paths.keys, b_.batch_count, a.paths.offsets, b_.path_count));

  // 4. Primary rays + NEE at the texel point.
  a.live = {&b_.active_a, &b_.path_count};
  const device::Buffer* spare = &b_.active_b;
  LUXEL_RETURN_IF_ERROR(launch(BakeKernel::raygen, cap));
  auto sort_by_direction = [&] {
    return sort_->enqueue(*a.live.active, device::Buffer(), *a.live.count, cap, kTagShift, 32);
  };
  if (nee) LUXEL_RETURN_IF_ERROR(trace_shadows(/*texel_point=*/!s_.plan.empty()));
  if (sort_directions) LUXEL_RETURN_IF_ERROR(sort_by_direction());

  // 5. Bounce loop: closest hit -> shade -> shadow rays -> compaction.
  for (int bounce = 0; bounce <= settings_.max_bounces; ++bounce) {
    LUXEL_RETURN_IF_ERROR(s_.tracer->closest_indexed(a.paths.rays, *a.live.active, *a.live.count,
                                                     kSlotMask, a.paths.hits, cap));
    LUXEL_RETURN_IF_ERROR(launch(BakeKernel::shade, cap));
    if (bounce == settings_.max_bounces) break;  // vertices past the limit only add emission
    if (nee) LUXEL_RETURN_IF_ERROR(trace_shadows(/*texel_point=*/false));
    if (compaction_) {
      // §5.1: keep only live paths; the new count stays on the device.
      const device::Buffer* next_count = a.live.count == &b_.count_a ? &b_.count_b : &b_.count_a;
      LUXEL_RETURN_IF_ERROR(compaction_->enqueue(a.paths.tagged, a.paths.alive, *a.live.count,
                                                 *spare, *next_count, cap));
      spare = std::exchange(a.live.active, spare);
      a.live.count = next_count;
      if (sort_directions) LUXEL_RETURN_IF_ERROR(sort_by_direction());
    } else if (sort_directions) {
      LUXEL_RETURN_IF_ERROR(device::cl_status(
          clEnqueueCopyBuffer(ctx_.queue(), a.paths.tagged.get(), a.live.active->get(), 0, 0,
                              cap * 4, 0, nullptr, nullptr),
          "copy tagged slots"));
      LUXEL_RETURN_IF_ERROR(sort_by_direction());
    }
  }

  // 6. Gather accumulation per covered texel (Listing 3.2).
  LUXEL_RETURN_IF_ERROR(launch(BakeKernel::accumulate, a.params.covered_count));
  paths_done_ += batch;
  return Status::ok();
}

// 7. Progress statistics: the kernel's per-work-group partials, summed here.
Status Baker::compute_stats(BakeProgress& progress) {
  BakeArgs& a = b_.args();
  a.params.paths = 0;
  const uint32_t covered = a.params.covered_count;
  const size_t groups = (covered + LUX_STATS_GROUP - 1) / LUX_STATS_GROUP;
  LUXEL_RETURN_IF_ERROR(launch(BakeKernel::accum_stats, groups * LUX_STATS_GROUP, LUX_STATS_GROUP));
  std::vector<cl::LuxAccumStats> partials(groups);
  LUXEL_RETURN_IF_ERROR(ctx_.read(a.accum.stats, partials));
  LUXEL_RETURN_IF_ERROR(ctx_.finish());
  sum_stats(partials, covered, settings_.reference != nullptr, progress);
  progress.paths = paths_done_;
  progress.mean_spp = static_cast<double>(paths_done_) / covered;
  return Status::ok();
}

Result<BakeResult> Baker::run(const BakeHooks& hooks) {
  LUXEL_RETURN_IF_ERROR(validate_settings(settings_));
  const auto t_setup = Clock::now();
  ctx_.timer().reset();
  LUXEL_RETURN_IF_ERROR(setup());
  BakeResult result;
  BakeProgress progress;
  double resumed_elapsed = 0;
  if (hooks.resume) {
    if (hooks.resume->fingerprint != hooks.fingerprint)
      return invalid_argument("checkpoint belongs to another scene or other settings");
    LUXEL_RETURN_IF_ERROR(b_.restore_state(ctx_, *hooks.resume, s_.info.covered_texels));
    paths_done_ = hooks.resume->paths_done;
    resumed_elapsed = hooks.resume->elapsed_s;
    progress.iteration = hooks.resume->iteration;
    result.series = series_from_checkpoint(*hooks.resume);
  }
  LUXEL_RETURN_IF_ERROR(ctx_.finish());
  result.setup_s = seconds_since(t_setup);

  const BakePolicy policy(settings_, hooks, s_.params.covered_count);
  const auto t_start = Clock::now();
  // Tracing time, continued across a resume.
  auto elapsed = [&] { return resumed_elapsed + seconds_since(t_start); };
  auto last_report = Clock::now(), last_snapshot = last_report, last_checkpoint = last_report;
  // Statistics, then the progress callback; false: the host cancels.
  auto report = [&](bool final_report) -> Result<bool> {
    LUXEL_RETURN_IF_ERROR(compute_stats(progress));
    progress.elapsed_s = elapsed();
    policy.estimate(progress, final_report);
    // The final report after a stopping rule repeats the last point: replace it.
    if (!result.series.empty() && result.series.back().paths == progress.paths)
      result.series.pop_back();
    result.series.push_back({progress.elapsed_s, progress.paths, progress.mean_spp,
                             progress.min_spp, progress.error, progress.rmse, progress.rel_mse});
    last_report = Clock::now();
    return !hooks.on_progress || hooks.on_progress(progress);
  };
  auto cancelled = [&] { return hooks.cancel && hooks.cancel->load(); };

  Termination why = Termination::kSamples;
  for (;;) {
    const uint64_t batch = policy.next_batch(s_.capacity, paths_done_);
    {
      std::unique_lock<std::mutex> turn;
      if (hooks.device_turn) turn = std::unique_lock<std::mutex>(*hooks.device_turn);
      LUXEL_RETURN_IF_ERROR(run_iteration(static_cast<uint32_t>(batch)));
      LUXEL_RETURN_IF_ERROR(ctx_.finish());
    }
    ++progress.iteration;
    if (auto stop = policy.stop_after_iteration(paths_done_, elapsed(), cancelled())) {
      why = *stop;
      break;
    }
    if (policy.report_due(seconds_since(last_report))) {
      auto keep_going = report(false);
      if (!keep_going) return keep_going.status();
      if (policy.error_reached(progress)) {
        why = Termination::kError;
        break;
      }
      if (!keep_going.value()) {
        why = Termination::kCancelled;
        break;
      }
    }
    if (policy.snapshot_due(seconds_since(last_snapshot))) {
      auto state = read_state();
      if (!state) return state.status();
      BakeSnapshot snap;
      snap.width = s_.atlas.width;
      snap.height = s_.atlas.height;
      fill_irradiance(s_, state.value().mean, 0, snap.irradiance);
      // The image's own statistics (error, min spp), not those of the last
      // progress report.
      LUXEL_RETURN_IF_ERROR(compute_stats(progress));
      snap.progress = progress;
      snap.progress.elapsed_s = elapsed();
      hooks.on_snapshot(snap);
      last_snapshot = Clock::now();
    }
    const bool requested = hooks.checkpoint_now && hooks.checkpoint_now->load();
    if (policy.checkpoint_due(seconds_since(last_checkpoint), requested)) {
      auto state = read_state();
      if (!state) return state.status();
      BakeCheckpoint& c = state.value();
      c.fingerprint = hooks.fingerprint;
      c.iteration = progress.iteration;
      c.elapsed_s = elapsed();
      series_to_checkpoint(result.series, c);
      hooks.on_checkpoint(c);
      last_checkpoint = Clock::now();
      // A host that checkpoints to stop (daemon shutdown) cancels in the
      // hook: stop here rather than trace an iteration the checkpoint lacks.
      if (cancelled()) {
        why = Termination::kCancelled;
        break;
      }
    }
  }
  result.seconds = elapsed();
  auto final_report = report(true);
  if (!final_report) return final_report.status();

  auto state = read_state();
  if (!state) return state.status();
  assemble_result(s_, settings_, state.value(), result);
  record_final_progress(progress, ctx_, result);
  result.termination = why;
  result.peak_device_bytes = s_.tracer->device_bytes() + b_.device_bytes() + sort_->device_bytes() +
                             (compaction_ ? compaction_->device_bytes() : 0);
  return result;
}

}  // namespace

Result<BakeResult> bake(const scene::Scene& scene, const BakeSettings& settings,
                        device::Context& ctx, const BakeHooks& hooks) {
  Baker baker(scene, settings, ctx);
  return baker.run(hooks);
}

Result<BakeResult> bake(const scene::Scene& scene, const BakeSettings& settings,
                        device::Context& ctx, const ProgressFn& on_progress) {
  BakeHooks hooks;
  hooks.on_progress = on_progress;
  return bake(scene, settings, ctx, hooks);
}

}  // namespace luxel::pipeline
