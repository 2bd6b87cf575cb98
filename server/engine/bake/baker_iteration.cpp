// One iteration of the Baker: the wavefront stages in order (module comment
// of kernels/bake.cl), adaptive allocation, and the progress statistics.
#include <cmath>
#include <utility>

#include "bake/baker.h"
#include "bake/iteration_stops.h"

namespace luxel::pipeline {

// Any-hit queries for the active list's shadow rays, then their results: into
// the paths' radiance, or (texel point with directional encodings) into the
// basis samples, which keep the light sample apart from the first segment.
Status Baker::trace_shadows(bool texel_point) {
  const LiveArgs& live = b_.args().live;
  const PathArgs& g = b_.args().paths;
  LUXEL_RETURN_IF_ERROR(s_.tracer->any_indexed(g.shadow_rays, *live.active, *live.count, kSlotMask,
                                               g.occluded, s_.capacity));
  return launch(texel_point ? BakeKernel::resolve_texel_shadows : BakeKernel::resolve_shadows,
                live_items());
}

// Work-items for the stage after a ray query: the live paths when the
// intersector read their count on the host, else the list's capacity (the
// kernels return past the count on the device).
size_t Baker::live_items() const {
  return s_.tracer->host_count().value_or(s_.capacity);
}

Result<bool> Baker::stop_point() {
  if (!interruptible_) return false;
  LUXEL_RETURN_IF_ERROR(ctx_.finish());
  const bool stop = stop_requested(*hooks_, !rerun_after_checkpoint_);
  gave_up_for_checkpoint_ = stop && !(hooks_->cancel && hooks_->cancel->load());
  return stop;
}

// Gives the iteration up (returns false) at a stage boundary when a stop is
// requested; nothing of it has reached the accumulation then.
#define LUXEL_STOP_POINT()             \
  do {                                 \
    auto stop_ = stop_point();         \
    if (!stop_) return stop_.status(); \
    if (stop_.value()) return false;   \
  } while (0)

// Adaptive sampling (kernels/bake/adaptive.h). Uniform until every texel
// of the tile has adaptive_min_samples (the uniform texel domain gives
// every texel k samples after k * covered paths), so that no texel's error
// estimate rests on fewer; then weights from the texels' relative error
// times their coverage, normalised by the tile's mean of that product. Everything here is a
// function of the path count and the device state (the statistics partials summed in a fixed
// order), never of timing: resumed and uninterrupted bakes allocate alike.
Result<bool> Baker::plan_allocation(uint32_t batch) {
  BakeKernelArgs& a = b_.args();
  const uint32_t covered = a.params.covered_count;
  if (paths_done_ < uint64_t{settings_.adaptive_min_samples} * covered) return false;
  std::vector<cl::LuxAccumStats> partials;
  LUXEL_RETURN_IF_ERROR(read_partials(partials));
  double err = 0, lum = 0;
  for (const cl::LuxAccumStats& p : partials) {
    err += p.rel_error_sum;  // coverage x relative error
    lum += p.luminance_sum;
  }
  const double mean_err = err / covered, mean_lum = lum / covered;
  if (!(mean_err > 0) || !std::isfinite(mean_err)) return false;  // nothing to equalise
  // Texels darker than kDarkFloor x the tile's mean luminance count their
  // error against that floor (absolute error, in units of the mean), the
  // brighter ones relative error: on the scenes of docs/accuracy.md
  // ("Adaptive sampling") 1.0 lowered both RMSE and relMSE against uniform
  // sampling everywhere, 0.1 cost RMSE on the Cornell boxes and 2.0 relMSE on
  // the city. kMix x the mean weight goes to every texel
  // (defensive sampling); one texel's error term is at most kCap x the
  // mean's. `unit` weight units stand for the mean error, halved until
  // paths x total weight stays below 2^63 (alloc_keys multiplies them).
  constexpr double kDarkFloor = 1.0, kMix = 0.2, kCap = 32;
  double unit = 128;
  while (unit > 1 && double(batch) * covered * (unit * (kCap + kMix) + 1) >= 9.2e18) unit /= 2;
  a.params.alloc_floor = static_cast<float>(kDarkFloor * std::max(mean_lum, 0.0));
  a.params.alloc_scale = static_cast<float>(unit / mean_err);
  a.params.alloc_cap = static_cast<float>(unit * kCap);
  a.params.alloc_mix = static_cast<float>(unit * kMix);
  return true;
}

// The keys of an adaptive iteration, already sorted by slot.
Status Baker::allocate_paths() {
  const size_t covered = b_.args().params.covered_count;
  const size_t grid = (covered + LUX_ALLOC_GROUP - 1) / LUX_ALLOC_GROUP * LUX_ALLOC_GROUP;
  LUXEL_RETURN_IF_ERROR(launch(BakeKernel::alloc_weights, grid, LUX_ALLOC_GROUP));
  LUXEL_RETURN_IF_ERROR(launch(BakeKernel::alloc_scan, LUX_ALLOC_GROUP, LUX_ALLOC_GROUP));
  return launch(BakeKernel::alloc_keys, grid, LUX_ALLOC_GROUP);
}

// One iteration of the wavefront pipeline (module comment of kernels/bake.cl).
Result<bool> Baker::run_iteration(uint32_t batch) {
  BakeKernelArgs& a = b_.args();
  interruptible_ = iteration_interruptible(*hooks_, batch, ctx_.info().is_gpu);
  rerun_after_checkpoint_ = std::exchange(gave_up_for_checkpoint_, false);
  const size_t cap = s_.capacity;
  const bool nee = s_.features.has(device::Feature::NEE);
  const bool sort_directions = settings_.sort_directions;
  bool adaptive = false;
  if (settings_.adaptive) {
    auto planned = plan_allocation(batch);
    if (!planned) return planned.status();
    adaptive = planned.value();
  }
  a.params.paths = batch;
  a.params.first_path = paths_done_;
  a.params.adaptive_pass = adaptive ? 1u : 0u;

  // 1. Texel domain, 2. radix sort by texel (keys are covered slots, which
  // ascend with texels; only the bits the slot range needs), 3. offset
  // buffer over slots (Listing 3.1). Adaptive iterations write the keys
  // in slot order (alloc_keys), so they skip the sort.
  LUXEL_RETURN_IF_ERROR(launch(BakeKernel::texel_domain, cap));
  LUXEL_STOP_POINT();
  const int32_t count = static_cast<int32_t>(batch);
  LUXEL_RETURN_IF_ERROR(ctx_.write(b_.batch_count, &count, sizeof count));
  if (adaptive)
    LUXEL_RETURN_IF_ERROR(allocate_paths());
  else
    LUXEL_RETURN_IF_ERROR(sort_->enqueue(a.paths.keys, device::Buffer(), b_.batch_count, cap, 0,
                                         RadixSort::bits_for(a.params.covered_count - 1)));
  LUXEL_STOP_POINT();
  LUXEL_RETURN_IF_ERROR(
      offset_buffer_->enqueue(a.paths.keys, b_.batch_count, a.paths.offsets, b_.path_count));
  LUXEL_STOP_POINT();

  // 4. Primary rays + NEE at the texel point.
  a.live = {&b_.active_a, &b_.path_count};
  const device::Buffer* spare = &b_.active_b;
  LUXEL_RETURN_IF_ERROR(launch(BakeKernel::raygen, batch));  // returns past the batch
  LUXEL_STOP_POINT();
  auto sort_by_direction = [&] {
    return sort_->enqueue(*a.live.active, device::Buffer(), *a.live.count, cap, kTagShift, 32);
  };
  if (nee) LUXEL_RETURN_IF_ERROR(trace_shadows(/*texel_point=*/!s_.plan.empty()));
  if (sort_directions) LUXEL_RETURN_IF_ERROR(sort_by_direction());
  LUXEL_STOP_POINT();

  // 5. Bounce loop: closest hit -> shade -> shadow rays -> compaction.
  for (int bounce = 0; bounce <= settings_.max_bounces; ++bounce) {
    LUXEL_RETURN_IF_ERROR(s_.tracer->closest_indexed(a.paths.rays, *a.live.active, *a.live.count,
                                                     kSlotMask, a.paths.hits, cap));
    LUXEL_STOP_POINT();
    LUXEL_RETURN_IF_ERROR(launch(BakeKernel::shade, live_items()));
    LUXEL_STOP_POINT();
    if (bounce == settings_.max_bounces) break;  // vertices past the limit only add emission
    if (nee) LUXEL_RETURN_IF_ERROR(trace_shadows(/*texel_point=*/false));
    LUXEL_STOP_POINT();
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
  return true;
}
#undef LUXEL_STOP_POINT

// 7. Progress statistics: the kernel's per-work-group partials, summed here.
Status Baker::read_partials(std::vector<cl::LuxAccumStats>& partials) {
  BakeKernelArgs& a = b_.args();
  a.params.paths = 0;
  const uint32_t covered = a.params.covered_count;
  const size_t groups = (covered + LUX_STATS_GROUP - 1) / LUX_STATS_GROUP;
  LUXEL_RETURN_IF_ERROR(launch(BakeKernel::accum_stats, groups * LUX_STATS_GROUP, LUX_STATS_GROUP));
  partials.resize(groups);
  LUXEL_RETURN_IF_ERROR(ctx_.read(a.accum.stats, partials));
  return ctx_.finish();
}

Status Baker::compute_stats(BakeProgress& progress) {
  const uint32_t covered = b_.args().params.covered_count;
  std::vector<cl::LuxAccumStats> partials;
  LUXEL_RETURN_IF_ERROR(read_partials(partials));
  sum_stats(partials, covered, settings_.reference != nullptr, progress);
  progress.paths = paths_done_;
  progress.mean_spp = static_cast<double>(paths_done_) / covered;
  return Status::ok();
}

}  // namespace luxel::pipeline
