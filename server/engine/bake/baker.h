// The iteration scheduler of one bake (bake.h's bake() and
// bake_probe_domain()), internal to bake/: it prepares the scene
// (bake_setup), owns the device buffers (bake_buffers) and kernels
// (bake_kernels), runs the wavefront stages of one iteration in order
// (baker_iteration.cpp), asks the policy (bake_policy) what is due after
// each, bakes the covered texels in tiles when their state does not fit the
// device-memory budget (baker_tiles.cpp, tile_plan.h) and denoises the result
// (baker_denoise.cpp); bake_assembly puts the result together.
#pragma once

#include <memory>
#include <utility>
#include <vector>

#include "bake/bake.h"
#include "bake/bake_assembly.h"
#include "bake/bake_buffers.h"
#include "bake/bake_kernels.h"
#include "bake/bake_policy.h"
#include "bake/bake_setup.h"
#include "bake/lightmap_layout.h"
#include "bake/primitives/offset_buffer.h"
#include "bake/primitives/radix_sort.h"
#include "bake/primitives/stream_compaction.h"
#include "bake/progressive_variance.h"
#include "bake/tile_plan.h"
#include "common/clock.h"
#include "post/denoise.h"
#include "post/oidn.h"

namespace luxel::pipeline {

class Baker {
 public:
  Baker(const LightmapLayout& layout, const BakeSettings& settings, device::Context& ctx,
        const ProbeDomain* probes = nullptr)
      : scene_(*layout.scene), layout_(layout), settings_(settings), ctx_(ctx), probes_(probes) {}

  // The bake, as named steps (bake.cpp): start (setup, resume or the first
  // tile), then per tile run_tile (iterations until a rule stops it, with
  // the reports, milestones, snapshots and checkpoints the policy says are
  // due) and finish_tile, then the final state, the result and the denoised
  // lightmap.
  Result<BakeResult> run(const BakeHooks& hooks);

 private:
  // Steps of run() (bake.cpp).
  Result<size_t> start();  // the index of the first tile to bake
  Result<Termination> run_tile(size_t ti, bool load);
  Result<bool> iterate(uint64_t batch);    // one iteration, in the device's turn
  Result<bool> report(bool final_report);  // false: the host cancels
  Status record_milestone(const Tile& tile);
  Status send_snapshot(const Tile& tile);
  Status write_checkpoint(size_t ti);
  Status finish_tile(const Tile& tile, bool last);
  void keep_final_state();
  // Denoises the result (settings.denoise) after releasing the path
  // buffers; returns the device bytes held while it ran (0: skipped).
  Result<size_t> denoise_result();  // baker_denoise.cpp
  double elapsed() const { return resumed_elapsed_ + seconds_since(t_start_); }
  bool cancelled() const { return hooks_->cancel && hooks_->cancel->load(); }
  BakeResult discarded();

  // Setup and tiles (baker_tiles.cpp).
  Status setup();
  Status launch(BakeKernel k, size_t global, size_t local = 64) {
    LUXEL_RETURN_IF_ERROR(kernels_.bind(k, b_.args()));
    return ctx_.launch(kernels_[k], global, local);
  }
  size_t live_items() const;
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
  // A checkpoint of the whole atlas from the current tile's state. It
  // borrows finished_'s arrays (no second copy of the finished tiles);
  // return_finished gives them back once the checkpoint is written.
  BakeCheckpoint tiled_checkpoint(const BakeCheckpoint& current, size_t tile);
  void return_finished(BakeCheckpoint& checkpoint);
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
    return denoise_method() != Denoise::kOff && settings_.filter == Filter::kBox;
  }
  // settings_.denoise with auto decided: oidn when its library loads in this
  // process (load_oidn keeps the first answer), else off (baker_denoise.cpp).
  Denoise denoise_method() const;
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
  // denoise_method() == oidn and the library loads (post/oidn.h): makes
  // oidn_ on the first call; otherwise records why in oidn_missing_ (the
  // a-trous filter runs instead). Decided once per bake.
  bool use_oidn();
  // The manifest's "denoise" object for what denoise() did last.
  std::string denoise_json(size_t two_point_texels) const;
  // OIDN's directional mode on each SH encoding of `result`
  // (coefficients_denoised); returns what the manifest says of them.
  Result<std::string> denoise_sh_encodings(BakeResult& result);
  // The manifest's "denoise" object when auto found no OIDN: why the map
  // stays raw.
  std::string auto_off_json() const;
  Result<BakeCheckpoint> read_state(CancelToken cancel = {}) {
    BakeCheckpoint c;
    LUXEL_RETURN_IF_ERROR(b_.read_state(ctx_, c, cancel));
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
  std::unique_ptr<Denoiser> denoiser_;  // on the first denoise()
  std::unique_ptr<OidnDenoiser> oidn_;  // denoise_method() == oidn, library found
  bool oidn_tried_ = false;
  std::string oidn_missing_;             // why oidn_ is null with denoise == oidn
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
    double error_sum = 0;            // sum of their texels' coverage x relative error
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
  // Tiled bakes: entry i sums the coverage of tiles [0, i)
  // (atlas::coverage_sum), the weights of the progress error; one entry per
  // tile boundary, so its size follows the plan, not the lightmap.
  std::vector<double> tile_coverage_;
  // The coverage of covered slots [0, slot), `slot` a tile boundary.
  double coverage_before(size_t slot) const;

  // The state of run() between its steps.
  BakeResult result_;
  const BakePolicy* policy_ = nullptr;  // the whole bake's rules (reports, snapshots, checkpoints)
  BakeProgress progress_;               // the whole bake's
  BakeProgress tile_progress_;          // the current tile's own figures (the error rule's)
  double resumed_elapsed_ = 0;          // tracing time before a resume
  SteadyClock::time_point t_start_, last_report_, last_snapshot_, last_checkpoint_;
};

}  // namespace luxel::pipeline
