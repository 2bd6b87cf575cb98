// The iteration scheduler of a bake: prepares the scene (bake_setup), owns
// the device buffers (bake_buffers) and kernels (bake_kernels), runs the
// wavefront stages of one iteration in order, and asks the policy
// (bake_policy) when to report, snapshot, checkpoint and stop; the result is
// put together by bake_assembly. When the per-texel state does not fit the
// device-memory budget, the covered texels are baked in tiles, one after
// another (bake/tile_plan.h has the turn policy).
#include "bake/bake.h"

#include <chrono>
#include <cmath>

#include "bake/bake_assembly.h"
#include "bake/bake_buffers.h"
#include "bake/bake_kernels.h"
#include "bake/bake_policy.h"
#include "bake/bake_setup.h"
#include "bake/iteration_stops.h"
#include "bake/lightmap_layout.h"
#include "bake/primitives/offset_buffer.h"
#include "bake/primitives/radix_sort.h"
#include "bake/primitives/stream_compaction.h"
#include "bake/progressive_variance.h"
#include "bake/resource_estimate.h"
#include "bake/tile_plan.h"
#include "post/denoise.h"

namespace luxel::pipeline {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

class Baker {
 public:
  Baker(const LightmapLayout& layout, const BakeSettings& settings, device::Context& ctx,
        const ProbeDomain* probes = nullptr)
      : scene_(*layout.scene), layout_(layout), settings_(settings), ctx_(ctx), probes_(probes) {}

  Result<BakeResult> run(const BakeHooks& hooks);

 private:
  Status setup();
  Status launch(BakeKernel k, size_t global, size_t local = 64) {
    LUXEL_RETURN_IF_ERROR(kernels_.bind(k, b_.args()));
    return ctx_.launch(kernels_[k], global, local);
  }
  Status plan_memory();
  // false: a stop was requested mid-iteration and the iteration was given
  // up before its accumulation (iteration_stops.h).
  Result<bool> run_iteration(uint32_t batch);
  // At a stage boundary of an interruptible iteration: waits for the device
  // and says whether to give the iteration up.
  Result<bool> stop_point();
  // Adaptive sampling: whether this iteration allocates by error (past the
  // warm-up, some error left), and its weight parameters into the params.
  Result<bool> plan_allocation(uint32_t batch);
  Status allocate_paths();
  Status trace_shadows(bool texel_point);
  Status read_partials(std::vector<cl::LuxAccumStats>& partials);
  Status compute_stats(BakeProgress& p);
  // The whole bake's progress from the current tile's (identity untiled).
  BakeProgress globalize(const BakeProgress& tile) const;
  // Device buffers held now: BVH, bake buffers, sort and compaction scratch.
  size_t device_bytes_held() const {
    return s_.tracer->device_bytes() + b_.device_bytes() + sort_->device_bytes() +
           (compaction_ ? compaction_->device_bytes() : 0);
  }
  bool tiled() const { return plan_.tiles.size() > 1; }
  // Restores a checkpoint: finished tiles into the result, the current
  // tile onto the device (loaded); returns the current tile's index.
  Result<size_t> resume_tiles(const BakeCheckpoint& c, BakeResult& result);
  // A checkpoint of the whole atlas from the current tile's state.
  BakeCheckpoint tiled_checkpoint(const BakeCheckpoint& current, size_t tile) const;
  static void append_state(BakeCheckpoint& to, const BakeCheckpoint& from);
  // settings_.denoise applied to a whole-atlas RGBA image with the variance
  // of each texel's mean (the guides are built and uploaded on the first
  // call). `two_point_texels`: how many variances are progressive_'s
  // two-point estimates (the manifest says so).
  Result<std::vector<float>> denoise(const std::vector<float>& rgba,
                                     const std::vector<float>& variance, size_t two_point_texels);
  // The denoiser's variances come from ProgressiveVariance (box filter; the
  // Gaussian filter's weighted samples keep the Welford variance).
  bool tracks_progressive_variance() const {
    return settings_.denoise != Denoise::kOff && settings_.filter == Filter::kBox;
  }
  // Variances for the denoiser of the whole atlas (`rgba`, `rel_error`):
  // Welford's from the relative errors, replaced by the two-point estimates
  // of the finished tiles (denoise_variance_) and, with `state`, of the
  // current tile from `begin`.
  std::vector<float> atlas_variance(const std::vector<float>& rgba,
                                    const std::vector<float>& rel_error,
                                    const BakeCheckpoint* state, size_t begin,
                                    size_t* two_point) const {
    *two_point = 0;
    std::vector<float> welford = texel_variance(rgba, rel_error);
    if (!tracks_progressive_variance()) return welford;
    std::vector<float> v = denoise_variance_;
    *two_point = two_point_texels_ + (state ? progressive_.fill(s_, *state, begin, v) : 0);
    return ProgressiveVariance::overlay(std::move(welford), v);
  }
  DenoiseParams denoise_params(size_t two_point_texels) const;
  Result<BakeCheckpoint> read_state() {
    BakeCheckpoint c;
    LUXEL_RETURN_IF_ERROR(b_.read_state(ctx_, c));
    c.paths_done = paths_done_;
    label_state(c);
    return c;
  }
  // What a state record says beside the arrays: its shard and the layout of
  // its encoding state (BakeCheckpoint::basis_layout).
  void label_state(BakeCheckpoint& c) const {
    c.shard_index = settings_.sharded() ? settings_.shard_index : 0;
    c.shard_count = settings_.sharded() ? settings_.shard_count : 1;
    c.basis_layout.clear();
    for (const cl::LuxEncoding& e : s_.plan.table)
      c.basis_layout.push_back(static_cast<uint32_t>(e.count) | static_cast<uint32_t>(e.solver)
                                                                    << 16);
  }
  // A state of every covered texel without a tile record (a merge of
  // shards, shards/shard_merge.h) restored into a tiled bake: tile
  // [begin, end)'s part of it, its paths the samples it holds.
  Status restore_whole_state(size_t begin, size_t end) {
    BakeCheckpoint k = slice_checkpoint(*whole_state_, begin, end);
    if (begin > 0) k.nonfinite = 0;  // counted once, with the first tile
    LUXEL_RETURN_IF_ERROR(b_.restore_state(ctx_, k, s_.info.covered_texels));
    paths_done_ = 0;
    for (uint32_t n : k.spp) paths_done_ += n;
    return Status::ok();
  }

  const scene::Scene& scene_;  // the layout's: split vertices when UVs were generated
  const LightmapLayout& layout_;
  const BakeSettings& settings_;
  device::Context& ctx_;
  const ProbeDomain* probes_;  // null: the lightmap's texel domain

  BakeSetup s_;
  BakeBuffers b_;
  BakeKernels kernels_;
  std::unique_ptr<RadixSort> sort_;
  std::unique_ptr<StreamCompaction> compaction_;  // null with compaction off
  std::unique_ptr<OffsetBuffer> offset_buffer_;
  std::unique_ptr<Denoiser> denoiser_;   // on the first denoise()
  ProgressiveVariance progressive_;      // milestones of the current tile
  std::vector<float> denoise_variance_;  // finished tiles' two-point variances (-1: none)
  size_t two_point_texels_ = 0;          // how many texels have one
  TilePlan plan_;
  size_t budget_ = 0;
  uint64_t paths_done_ = 0;  // of the current tile (of the bake, untiled)
  const BakeHooks* hooks_ = nullptr;
  bool interruptible_ = false;           // the current iteration checks for stops between stages
  bool gave_up_for_checkpoint_ = false;  // the last iteration, for a checkpoint
  bool rerun_after_checkpoint_ = false;  // this iteration re-runs one given up for a checkpoint

  // Tiled bakes: the finished tiles' share of the progress statistics.
  struct Done {
    size_t slots = 0;                // covered slots of the finished tiles
    uint64_t paths = 0;              // their paths
    double error_sum = 0;            // sum of their texels' relative errors
    double sq_sum = 0, rel_sum = 0;  // with a reference: RMSE^2 and relMSE sums
    uint32_t min_spp = 0xFFFFFFFFu;
    uint64_t nonfinite = 0;
  } done_;
  // Tiled bakes with checkpoints: the finished tiles' state (slots
  // [0, done_.slots)), for the checkpoints of later tiles.
  bool keep_finished_ = false;
  BakeCheckpoint finished_;
  // Resumed from a whole-atlas state without a tile record into a tiled plan.
  const BakeCheckpoint* whole_state_ = nullptr;
  // With a reference: the RMSE^2 and relMSE sums of each tile while black.
  std::vector<std::pair<double, double>> black_ref_;
};

Result<std::vector<float>> Baker::denoise(const std::vector<float>& rgba,
                                          const std::vector<float>& variance,
                                          size_t two_point_texels) {
  if (!denoiser_) {
    auto d = Denoiser::create(ctx_, build_denoise_guides(scene_, s_.atlas, s_.info));
    if (!d) return d.status();
    denoiser_ = std::move(d.value());
  }
  return denoiser_->run(rgba, variance, denoise_params(two_point_texels));
}

DenoiseParams Baker::denoise_params(size_t two_point_texels) const {
  DenoiseParams p;
  if (tracks_progressive_variance())
    p.variance_source = strprintf(
        "two-point progressive estimate (y_n - y_s)^2 s / (n - s) for %zu of %zu covered texels "
        "(bake/progressive_variance.h), Welford for the rest",
        two_point_texels, s_.info.covered_texels.size());
  return p;
}

Status Baker::setup() {
  auto setup = prepare_bake(scene_, layout_.atlas, settings_, ctx_, probes_);
  if (!setup) return setup.status();
  s_ = std::move(setup.value());
  auto sort = RadixSort::create(ctx_, s_.capacity);
  if (!sort) return sort.status();
  sort_ = std::move(sort.value());
  if (settings_.compaction) {
    auto compaction = StreamCompaction::create(ctx_, s_.capacity);
    if (!compaction) return compaction.status();
    compaction_ = std::move(compaction.value());
  }
  LUXEL_RETURN_IF_ERROR(plan_memory());
  auto buffers =
      BakeBuffers::create(ctx_, scene_, s_, settings_, {plan_.max_slots, plan_.max_words});
  if (!buffers) return buffers.status();
  b_ = std::move(buffers.value());
  auto offsets = OffsetBuffer::create(ctx_, s_.capacity, static_cast<uint32_t>(plan_.max_slots));
  if (!offsets) return offsets.status();
  offset_buffer_ = std::move(offsets.value());
  auto kernels = BakeKernels::create(ctx_, s_.features);
  if (!kernels) return kernels.status();
  kernels_ = std::move(kernels.value());
  return Status::ok();
}

// The tiles of the covered texels under the device-memory budget.
Status Baker::plan_memory() {
  const device::DeviceInfo& info = ctx_.info();
  budget_ = memory_budget(settings_, info.global_mem_bytes);
  auto fixed = BakeBuffers::fixed_bytes(ctx_, scene_, s_, settings_);
  if (!fixed) return fixed.status();
  // The batch's buffers, checked as at submit (resource_estimate.h).
  const PathStateBytes per_path = path_state_bytes(!s_.plan.empty());
  const size_t path_bytes = s_.capacity * per_path.per_path;
  LUXEL_RETURN_IF_ERROR(check_path_state(s_.capacity, per_path,
                                         fixed.value() - std::min(fixed.value(), path_bytes),
                                         budget_, info.max_alloc_bytes));
  MemoryModel m;
  m.budget = budget_;
  m.max_alloc = info.max_alloc_bytes;
  m.fixed = fixed.value() + s_.tracer->device_bytes() + sort_->device_bytes() +
            (compaction_ ? compaction_->device_bytes() : 0);
  m.per_slot = BakeBuffers::per_slot_bytes(s_);
  m.largest_per_slot = BakeBuffers::largest_per_slot_bytes(s_);
  // The Gaussian filter gathers neighbours' paths of the same iteration,
  // across tile edges too.
  m.tileable = settings_.filter != Filter::kGaussian;
  m.why_not =
      "settings.filter 'gaussian' gathers the paths of neighbouring texels, which may lie "
      "in another tile (use the box filter, or a larger budget)";
  auto plan = plan_tiles(s_.info, m);
  if (!plan) return plan.status();
  plan_ = std::move(plan.value());
  if (!tiled() || !settings_.reference) return Status::ok();
  const std::vector<float>& ref = *settings_.reference;
  for (const Tile& t : plan_.tiles) {
    double sq = 0, rel = 0;
    for (size_t k = t.begin; k < t.end; ++k) {
      const float* r = &ref[size_t{s_.info.covered_texels[k]} * 4];
      for (int c = 0; c < 3; ++c) {
        const double r2 = double{r[c]} * r[c];
        sq += r2 / 3.0;
        rel += r2 / (r2 + 1e-2) / 3.0;
      }
    }
    black_ref_.push_back({sq, rel});
  }
  return Status::ok();
}

BakeProgress Baker::globalize(const BakeProgress& tile) const {
  if (!tiled()) return tile;
  BakeProgress p = tile;
  const double n = b_.args().params.covered_count;
  const double all = static_cast<double>(s_.info.covered_texels.size());
  const size_t black = s_.info.covered_texels.size() - done_.slots - b_.args().params.covered_count;
  double sq_black = 0, rel_black = 0;
  for (size_t i = plan_.tiles.size(); i-- > 0 && plan_.tiles[i].begin >= done_.slots + n;) {
    if (i < black_ref_.size()) {
      sq_black += black_ref_[i].first;
      rel_black += black_ref_[i].second;
    }
  }
  p.paths = done_.paths + tile.paths;
  p.mean_spp = static_cast<double>(p.paths) / all;
  p.min_spp = black > 0 ? 0 : std::min(done_.min_spp, tile.min_spp);
  p.error = (done_.error_sum + tile.error * n + static_cast<double>(black)) / all;
  if (settings_.reference) {
    p.rmse = std::sqrt((done_.sq_sum + tile.rmse * tile.rmse * n + sq_black) / all);
    p.rel_mse = (done_.rel_sum + tile.rel_mse * n + rel_black) / all;
  }
  return p;
}

void Baker::append_state(BakeCheckpoint& to, const BakeCheckpoint& from) {
  to.mean.insert(to.mean.end(), from.mean.begin(), from.mean.end());
  to.m2.insert(to.m2.end(), from.m2.begin(), from.m2.end());
  to.weight.insert(to.weight.end(), from.weight.begin(), from.weight.end());
  to.spp.insert(to.spp.end(), from.spp.begin(), from.spp.end());
  to.basis.insert(to.basis.end(), from.basis.begin(), from.basis.end());
}

BakeCheckpoint Baker::tiled_checkpoint(const BakeCheckpoint& current, size_t ti) const {
  BakeCheckpoint c = finished_;
  label_state(c);
  c.width = current.width;
  c.height = current.height;
  c.paths_done = current.paths_done;
  c.nonfinite = current.nonfinite;
  append_state(c, current);
  const size_t n = s_.info.covered_texels.size();
  const size_t stride = s_.params.encoding_count == 0 ? 0 : s_.params.basis_stride;
  c.mean.resize(n, cl::float4{});
  c.m2.resize(n, cl::float4{});
  c.weight.resize(n, cl::float2{});
  c.spp.resize(n, 0);
  c.basis.resize(n * stride, cl::float4{});
  const Tile& t = plan_.tiles[ti];
  c.tile.assign(kTileFields, 0.0);
  c.tile[kTileIndex] = static_cast<double>(ti);
  c.tile[kTileBegin] = static_cast<double>(t.begin);
  c.tile[kTileEnd] = static_cast<double>(t.end);
  c.tile[kTileCount] = static_cast<double>(plan_.tiles.size());
  c.tile[kTileDonePaths] = static_cast<double>(done_.paths);
  c.tile[kTileDoneNonfinite] = static_cast<double>(done_.nonfinite);
  c.tile[kTileDoneError] = done_.error_sum;
  c.tile[kTileDoneSq] = done_.sq_sum;
  c.tile[kTileDoneRel] = done_.rel_sum;
  c.tile[kTileDoneMinSpp] = static_cast<double>(done_.min_spp);
  return c;
}

Result<size_t> Baker::resume_tiles(const BakeCheckpoint& c, BakeResult& result) {
  const auto other_plan = [&] {
    return invalid_argument(
        strprintf("checkpoint was written under another tile plan than this bake's %zu tile(s) "
                  "(settings.device_memory_budget_mib or the device changed)",
                  plan_.tiles.size()));
  };
  if (c.tile.empty()) {
    if (tiled() && c.mean.size() == s_.info.covered_texels.size() && !c.per_texel) {
      whole_state_ = &c;
      LUXEL_RETURN_IF_ERROR(b_.load_tile(ctx_, s_, plan_.tiles[0].begin, plan_.tiles[0].end));
      LUXEL_RETURN_IF_ERROR(restore_whole_state(plan_.tiles[0].begin, plan_.tiles[0].end));
      return size_t{0};
    }
    if (tiled()) return other_plan();
    LUXEL_RETURN_IF_ERROR(b_.load_tile(ctx_, s_, plan_.tiles[0].begin, plan_.tiles[0].end));
    LUXEL_RETURN_IF_ERROR(b_.restore_state(ctx_, c, s_.info.covered_texels));
    return size_t{0};
  }
  const auto ti = static_cast<size_t>(c.tile[kTileIndex]);
  if (c.tile[kTileCount] != static_cast<double>(plan_.tiles.size()) || ti >= plan_.tiles.size() ||
      c.tile[kTileBegin] != static_cast<double>(plan_.tiles[ti].begin) ||
      c.tile[kTileEnd] != static_cast<double>(plan_.tiles[ti].end) ||
      c.mean.size() != s_.info.covered_texels.size())
    return other_plan();
  const Tile& t = plan_.tiles[ti];
  if (t.begin > 0) {
    BakeCheckpoint done = slice_checkpoint(c, 0, t.begin);
    done.nonfinite = static_cast<uint64_t>(c.tile[kTileDoneNonfinite]);
    write_state(s_, done, 0, result);
    if (keep_finished_) finished_ = std::move(done);
  }
  done_.slots = t.begin;
  done_.paths = static_cast<uint64_t>(c.tile[kTileDonePaths]);
  done_.nonfinite = static_cast<uint64_t>(c.tile[kTileDoneNonfinite]);
  done_.error_sum = c.tile[kTileDoneError];
  done_.sq_sum = c.tile[kTileDoneSq];
  done_.rel_sum = c.tile[kTileDoneRel];
  done_.min_spp = static_cast<uint32_t>(c.tile[kTileDoneMinSpp]);
  LUXEL_RETURN_IF_ERROR(b_.load_tile(ctx_, s_, t.begin, t.end));
  LUXEL_RETURN_IF_ERROR(
      b_.restore_state(ctx_, slice_checkpoint(c, t.begin, t.end), s_.info.covered_texels));
  return ti;
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
// estimate rests on fewer; then weights from the texels' relative error,
// normalised by the tile's mean error. Everything here is a function of the
// path count and the device state (the statistics partials summed in a
// fixed order), never of timing: resumed and uninterrupted bakes allocate
// alike.
Result<bool> Baker::plan_allocation(uint32_t batch) {
  BakeArgs& a = b_.args();
  const uint32_t covered = a.params.covered_count;
  if (paths_done_ < uint64_t{settings_.adaptive_min_samples} * covered) return false;
  std::vector<cl::LuxAccumStats> partials;
  LUXEL_RETURN_IF_ERROR(read_partials(partials));
  double err = 0, lum = 0;
  for (const cl::LuxAccumStats& p : partials) {
    err += p.rel_error_sum;
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
  BakeArgs& a = b_.args();
  interruptible_ = iteration_interruptible(*hooks_, batch, ctx_.info().is_gpu);
  rerun_after_checkpoint_ = std::exchange(gave_up_for_checkpoint_, false);
  const size_t cap = s_.capacity;
  const bool nee = s_.features.has("NEE");
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
  LUXEL_RETURN_IF_ERROR(launch(BakeKernel::raygen, cap));
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
    LUXEL_RETURN_IF_ERROR(launch(BakeKernel::shade, cap));
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
  BakeArgs& a = b_.args();
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

Result<BakeResult> Baker::run(const BakeHooks& hooks) {
  LUXEL_RETURN_IF_ERROR(validate_settings(settings_));
  hooks_ = &hooks;
  const auto t_setup = Clock::now();
  ctx_.timer().reset();
  LUXEL_RETURN_IF_ERROR(setup());
  // Shards keep every tile's state for BakeResult::final_state.
  keep_finished_ = (tiled() && static_cast<bool>(hooks.on_checkpoint)) || settings_.sharded() ||
                   hooks.keep_final_state;
  BakeResult result;
  begin_result(s_, result);
  BakeProgress progress;  // the whole bake's
  double resumed_elapsed = 0;
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
    auto tile = resume_tiles(*hooks.resume, result);
    if (!tile) return tile.status();
    first_tile = tile.value();
    if (!whole_state_) paths_done_ = hooks.resume->paths_done;
    resumed_elapsed = hooks.resume->elapsed_s;
    progress.iteration = hooks.resume->iteration;
    result.series = series_from_checkpoint(*hooks.resume);
  } else {
    LUXEL_RETURN_IF_ERROR(b_.load_tile(ctx_, s_, plan_.tiles[0].begin, plan_.tiles[0].end));
  }
  LUXEL_RETURN_IF_ERROR(ctx_.finish());
  result.setup_s = seconds_since(t_setup);

  const BakePolicy policy(settings_, hooks, s_.params.covered_count);
  const auto t_start = Clock::now();
  // Tracing time, continued across a resume.
  auto elapsed = [&] { return resumed_elapsed + seconds_since(t_start); };
  auto last_report = Clock::now(), last_snapshot = last_report, last_checkpoint = last_report;
  // Statistics, then the progress callback; false: the host cancels.
  // `tile_progress` gets the current tile's own figures (the error rule's).
  BakeProgress tile_progress;
  auto report = [&](bool final_report) -> Result<bool> {
    LUXEL_RETURN_IF_ERROR(compute_stats(tile_progress));
    const uint32_t iteration = progress.iteration;
    progress = globalize(tile_progress);
    progress.iteration = iteration;
    progress.elapsed_s = elapsed();
    progress.device_bytes = device_bytes_held();
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
  for (size_t ti = first_tile; ti < plan_.tiles.size(); ++ti) {
    const Tile& tile = plan_.tiles[ti];
    // The tile's stopping rules (tile_plan.h): its texels' samples, its
    // share of the time budget, the target error on its texels.
    BakeSettings tile_settings = settings_;
    if (tiled() && settings_.time_budget_s > 0)
      tile_settings.time_budget_s = settings_.time_budget_s * static_cast<double>(tile.end) /
                                    static_cast<double>(s_.info.covered_texels.size());
    const BakePolicy tile_policy(tile_settings, hooks, tile.end - tile.begin);
    progressive_.reset();
    if (ti > first_tile) {
      LUXEL_RETURN_IF_ERROR(b_.load_tile(ctx_, s_, tile.begin, tile.end));
      paths_done_ = 0;
      if (whole_state_) LUXEL_RETURN_IF_ERROR(restore_whole_state(tile.begin, tile.end));
    }
    for (;;) {
      if (hooks.finish_now && hooks.finish_now->load()) {
        why = Termination::kStopped;
        break;
      }
      const uint64_t batch = tile_policy.next_batch(s_.capacity, paths_done_);
      // Resumed with the samples already traced (a merge of shards): the
      // outputs come from the restored state, no iteration runs.
      if (batch == 0) {
        why = Termination::kSamples;
        break;
      }
      bool completed = true;
      {
        std::unique_lock<std::mutex> turn;
        if (hooks.device_turn) turn = std::unique_lock<std::mutex>(*hooks.device_turn);
        auto ran = run_iteration(static_cast<uint32_t>(batch));
        if (!ran) return ran.status();
        completed = ran.value();
        LUXEL_RETURN_IF_ERROR(ctx_.finish());
      }
      // Given up mid-iteration: cancelled, or a checkpoint first (then the
      // same iteration runs again: same first path, same bits).
      if (!completed && cancelled()) {
        why = Termination::kCancelled;
        break;
      }
      if (completed) ++progress.iteration;
      if (auto stop = tile_policy.stop_after_iteration(paths_done_, elapsed(), cancelled())) {
        why = *stop;
        break;
      }
      // A milestone of the denoiser's variance estimate when the tile's
      // mean count has doubled (bake/progressive_variance.h).
      if (completed && tracks_progressive_variance()) {
        const double mean_spp =
            static_cast<double>(paths_done_) / static_cast<double>(tile.end - tile.begin);
        if (progressive_.due(mean_spp)) {
          auto state = read_state();
          if (!state) return state.status();
          progressive_.record(state.value(), mean_spp);
        }
      }
      if (policy.report_due(seconds_since(last_report))) {
        auto keep_going = report(false);
        if (!keep_going) return keep_going.status();
        if (tile_policy.error_reached(tile_progress)) {
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
        snap.pages = s_.atlas.pages;
        snap.irradiance = result.irradiance;  // the finished tiles (zero untiled)
        fill_irradiance(s_, state.value().mean, tile.begin, snap.irradiance);
        if (hooks.denoise_snapshots && settings_.denoise != Denoise::kOff) {
          std::vector<float> rel_error = result.rel_error;
          fill_rel_error(s_, state.value(), tile.begin, rel_error);
          size_t two_point = 0;
          const std::vector<float> variance =
              atlas_variance(snap.irradiance, rel_error, &state.value(), tile.begin, &two_point);
          std::unique_lock<std::mutex> turn;
          if (hooks.device_turn) turn = std::unique_lock<std::mutex>(*hooks.device_turn);
          auto filtered = denoise(snap.irradiance, variance, two_point);
          if (!filtered) return filtered.status();
          snap.irradiance = std::move(filtered.value());
          snap.denoised = true;
        }
        // The image's own statistics (error, min spp), not those of the last
        // progress report.
        LUXEL_RETURN_IF_ERROR(compute_stats(tile_progress));
        snap.progress = globalize(tile_progress);
        snap.progress.iteration = progress.iteration;
        snap.progress.elapsed_s = elapsed();
        hooks.on_snapshot(snap);
        last_snapshot = Clock::now();
      }
      const bool requested = hooks.checkpoint_now && hooks.checkpoint_now->load();
      if (policy.checkpoint_due(seconds_since(last_checkpoint), requested)) {
        auto state = read_state();
        if (!state) return state.status();
        if (tiled()) state.value() = tiled_checkpoint(state.value(), ti);
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
    // The tile's state into the result; its statistics into done_.
    const bool last = ti + 1 == plan_.tiles.size() || why == Termination::kCancelled;
    if (last) {
      result.seconds = elapsed();
      auto final_report = report(true);
      if (!final_report) return final_report.status();
    } else {
      LUXEL_RETURN_IF_ERROR(compute_stats(tile_progress));
    }
    auto state = read_state();
    if (!state) return state.status();
    write_state(s_, state.value(), tile.begin, result);
    if (tracks_progressive_variance())
      two_point_texels_ += progressive_.fill(s_, state.value(), tile.begin, denoise_variance_);
    if (keep_finished_) append_state(finished_, state.value());
    const double n = static_cast<double>(tile.end - tile.begin);
    done_.slots = tile.end;
    done_.paths += paths_done_;
    done_.nonfinite += state.value().nonfinite;
    done_.error_sum += tile_progress.error * n;
    if (settings_.reference) {
      done_.sq_sum += tile_progress.rmse * tile_progress.rmse * n;
      done_.rel_sum += tile_progress.rel_mse * n;
    }
    done_.min_spp = std::min(done_.min_spp, tile_progress.min_spp);
    if (last) break;
  }
  if ((settings_.sharded() || hooks.keep_final_state) && why != Termination::kCancelled) {
    auto state = std::make_shared<BakeCheckpoint>();
    BakeCheckpoint& f = *state;
    append_state(f, finished_);
    f.fingerprint = hooks.fingerprint;
    label_state(f);
    f.width = static_cast<uint32_t>(s_.atlas.width);
    f.height = static_cast<uint32_t>(s_.atlas.height);
    f.paths_done = done_.paths;
    f.iteration = progress.iteration;
    f.elapsed_s = result.seconds;
    f.nonfinite = done_.nonfinite;
    series_to_checkpoint(result.series, f);
    result.final_state = std::move(state);
  }
  finish_result(s_, settings_, result);
  // Device memory of the bake (with a snapshot denoiser, held beside it).
  size_t peak = device_bytes_held() + (denoiser_ ? denoiser_->device_bytes() : 0);
  if (settings_.denoise != Denoise::kOff) {
    // The path buffers and sort/compaction scratch are done with: free them,
    // so the denoiser's buffers take their place within the budget.
    { BakeBuffers released = std::move(b_); }
    sort_.reset();
    compaction_.reset();
    offset_buffer_.reset();
    const size_t texels = size_t(s_.atlas.width) * size_t(s_.atlas.height);
    const size_t after = s_.tracer->device_bytes() + texels * Denoiser::kBytesPerTexel;
    if (!denoiser_ && after > budget_) {
      result.denoise_json = strprintf(
          R"({"method":"atrous","skipped":"the denoiser needs %zu bytes beside the BVH, over the device-memory budget of %zu"})",
          after, budget_);
    } else {
      const auto t_denoise = Clock::now();
      std::unique_lock<std::mutex> turn;
      if (hooks.device_turn) turn = std::unique_lock<std::mutex>(*hooks.device_turn);
      size_t two_point = 0;
      const std::vector<float> variance =
          atlas_variance(result.irradiance, result.rel_error, nullptr, 0, &two_point);
      auto filtered = denoise(result.irradiance, variance, two_point);
      if (!filtered) return filtered.status();
      result.irradiance_denoised = std::move(filtered.value());
      result.denoise_variance = variance;
      result.denoise_json = denoise_params(two_point).describe_json();
      result.denoise_s = seconds_since(t_denoise);
      peak = std::max(peak, s_.tracer->device_bytes() + denoiser_->device_bytes());
    }
  }
  record_final_progress(progress, ctx_, result);
  result.termination = why;
  result.tiles = plan_.tiles.size();
  result.batch_paths = s_.capacity;
  result.device_memory_budget = budget_;
  result.peak_device_bytes = peak;
  return result;
}

}  // namespace

Result<BakeResult> bake(const scene::Scene& scene, const BakeSettings& settings,
                        device::Context& ctx, const BakeHooks& hooks) {
  const auto t0 = Clock::now();
  auto layout = lay_out_lightmap(scene, settings);
  if (!layout) return layout.status();
  const double layout_s = seconds_since(t0);
  if (hooks.on_layout) hooks.on_layout(describe_lightmap_layout(layout.value()));
  Baker baker(layout.value(), settings, ctx);
  auto result = baker.run(hooks);
  if (!result) return result;
  result.value().uv_layout = layout.value().generated;
  if (settings.seam_stitch) {
    const auto t_seams = Clock::now();
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
