// The in-process bake engine: a progressive wavefront lightmap path tracer
// (thesis Ch. 3-6) over OpenCL. No gRPC here; the CLI (`luxel bake --local`)
// and the service drive it the same way.
//
//   Result<BakeResult> r = bake(scene, settings, ctx, on_progress);
//
// Deterministic: the same scene, settings (seed included) and device give
// bit-identical lightmaps, whatever the timing (stopping on time or error
// decides only HOW MANY iterations run, never what an iteration computes).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "atlas/atlas.h"
#include "atlas/seams.h"
#include "bake/bake_setup.h"
#include "bake/lightmap_layout.h"
#include "common/status.h"
#include "device/context.h"
#include "scene/scene.h"
#include "settings/bake_settings.h"
#include "shards/checkpoint.h"

namespace luxel::pipeline {

struct BakeProgress {
  double elapsed_s = 0;
  uint64_t paths = 0;    // paths traced so far
  double mean_spp = 0;   // mean samples per covered texel
  uint32_t min_spp = 0;  // minimum over covered texels
  double error = 1;      // mean relative standard error over covered texels
  double rmse = -1;      // with a reference: RMSE over covered texels and RGB (-1: none)
  double rel_mse = -1;   // with a reference: mean (x - ref)^2 / (ref^2 + 1e-2) (-1: none)
  double eta_s = -1;     // estimated seconds left (-1: unknown)
  double fraction = 0;   // progress towards the nearest stopping rule, [0, 1]
  uint32_t iteration = 0;
  size_t device_bytes = 0;  // device buffers the bake holds (BVH included)
};

// kStopped: the host asked the bake to finish with what it has traced
// (BakeHooks::finish_now; CancelBake with finish, or a coordinator's stop
// rule across shards): a complete result, like kTime.
enum class Termination { kSamples, kTime, kError, kCancelled, kStopped };
const char* termination_name(Termination t);

// One point of the error-against-time series (reported with every bake).
struct ErrorSample {
  double elapsed_s;
  uint64_t paths;
  double mean_spp;
  uint32_t min_spp;
  double error;
  double rmse = -1, rel_mse = -1;  // -1 without a reference
};

// One directional encoding of a finished bake.
struct EncodedLightmap {
  std::string name;                 // "sh2", "sg12", "ambient-dice9", ...
  int count = 0;                    // coefficients per colour channel
  std::vector<float> coefficients;  // texel-major, count * RGB (lobe-major), row 0 = top
  // The coefficients through Open Image Denoise's directional mode (SH
  // encodings when the bake denoises with OIDN, post/oidn.h run_sh); empty
  // otherwise (the manifest's denoise.directional says why).
  std::vector<float> coefficients_denoised;
  std::string manifest_json;  // basis, frame, solver (without the file entry)
  double residual_rms = -1;   // progressive solvers: mean over covered texels of the running
                              // residual RMS (luminance); -1 for projection
};

struct BakeResult {
  int width = 0, height = 0;
  std::vector<float>
      irradiance;                // RGBA, row 0 = top; A = fraction of the texel covered by geometry
  std::vector<float> samples;    // samples per texel (own-texel paths)
  std::vector<float> rel_error;  // relative standard error per texel (0 where uncovered)
  // settings.denoise != off: `irradiance` filtered by the denoiser (denoise.h),
  // same layout; empty otherwise, or when the denoiser's buffers would not
  // fit the device-memory budget beside the BVH. denoise_json describes the
  // filter, or why it was skipped (manifest "denoise").
  std::vector<float> irradiance_denoised;
  // The variance of each texel's mean that the denoiser was given (width *
  // height; bake/progressive_variance.h); empty without denoising.
  std::vector<float> denoise_variance;
  std::string denoise_json;
  double denoise_s = 0;  // guides + filter, wall seconds (the launches are in kernel_ms)
  atlas::Atlas atlas;
  size_t covered_texels = 0;
  // Generated lightmap UVs (null when the file's TEXCOORD_1 was used):
  // what lightmap_layout.h decided, for the manifest and the written-back glTF.
  std::shared_ptr<const GeneratedUvLayout> uv_layout;
  // The lightmap's UV seams (atlas/seams.h) when settings.seam_stitch: the
  // outputs stitch them (post/bake_seams.h). Null when off.
  std::shared_ptr<const atlas::SeamSet> seams;
  double seam_find_s = 0;  // seconds finding them

  Termination termination = Termination::kSamples;
  double seconds = 0;
  uint64_t paths = 0;
  double mean_spp = 0;
  uint32_t min_spp = 0;
  double error = 1;
  double rmse = -1, rel_mse = -1;  // against the reference, -1 without one
  uint64_t nonfinite_dropped = 0;
  std::vector<ErrorSample> series;
  std::vector<EncodedLightmap> encodings;  // directional encodings, in the requested order
  // Probe domain only: per probe LUX_PROBE_VIS_BINS bins (shared/probe.h) of
  // (mean distance, mean squared distance, samples, 0); empty for lightmaps.
  std::vector<float> probe_visibility;
  size_t basis_bytes_per_texel = 0;  // device state of all encodings per texel

  // Distributed bakes (settings.shard_count > 1, shards/shard_merge.h):
  // the shard's final per-texel accumulators, every covered texel (all
  // tiles complete), fingerprint from the hooks, shard fields set; what a
  // coordinator merges. Null for cancelled bakes, and for whole bakes
  // unless BakeHooks::keep_final_state.
  std::shared_ptr<const BakeCheckpoint> final_state;

  std::string features;  // compiled bake features ("light_emissive, nee, ...")
  std::string device;
  std::string intersector;  // backend of the ray queries ("embree", "opencl")
  size_t sample_info_bytes = 0;
  size_t peak_device_bytes = 0;     // device buffers held by the bake (BVH included)
  size_t device_memory_budget = 0;  // bytes the bake was planned within
  size_t tiles = 1;                 // tiles of covered texels baked in turn (tile_plan.h)
  size_t batch_paths = 0;           // path slots of one iteration (paths_per_iteration resolved)
  double setup_s = 0;               // import excluded: atlas, BVH, uploads, program builds
  std::string kernel_table;         // per-kernel timing table (Table 5.4 style)
  std::vector<std::pair<std::string, double>> kernel_ms;  // name -> total ms
};

// Called every settings.progress_interval_s (and once at the end). Return
// false to cancel the bake; the result then holds what was accumulated.
using ProgressFn = std::function<bool(const BakeProgress&)>;

// A progressive image of the bake so far (not dilated).
struct BakeSnapshot {
  int width = 0, height = 0;
  int pages = 1;                  // lightmap pages stacked from the top, height / pages rows each
  std::vector<float> irradiance;  // RGBA like BakeResult::irradiance
  bool denoised = false;          // irradiance went through the denoiser (BakeHooks)
  BakeProgress progress;
};

// Everything a long-running host (the daemon) hooks into a bake. All
// callbacks run on the bake's thread between iterations.
struct BakeHooks {
  ProgressFn on_progress;  // every settings.progress_interval_s
  // Once, when the lightmap layout is decided (before the first path): its
  // describe_lightmap_layout() line (lightmap_layout.h).
  std::function<void(const std::string&)> on_layout;
  double snapshot_interval_s = 0;  // 0: no snapshots
  std::function<void(const BakeSnapshot&)> on_snapshot;
  // Snapshots carry the denoised lightmap (settings.denoise != off) instead
  // of the raw one: previews only, the result keeps both.
  bool denoise_snapshots = false;
  double checkpoint_interval_s = 0;  // 0: no periodic checkpoints
  std::function<void(const BakeCheckpoint&)> on_checkpoint;
  const std::atomic<bool>* checkpoint_now = nullptr;  // set: checkpoint after the current iteration
  std::string fingerprint;                            // stored in checkpoints (scene + settings)
  const BakeCheckpoint* resume = nullptr;             // continue from this state
  // Set to stop: at the next stage of the current iteration, or during
  // setup (layout, UV generation, BVH build, buffers: common/cancel.h), where
  // bake() then fails with cancelled_error.
  const std::atomic<bool>* cancel = nullptr;
  // The host throws a cancelled bake away (the daemon): return at once,
  // with termination, seconds and paths only, without the final report,
  // the state's read-back, the encodings' solve or the denoise (seconds at
  // 2048^2 with directional encodings). Off: the result holds what was
  // accumulated.
  bool discard_cancelled = false;
  // Set: stop after the current iteration (or before the first, when set
  // already) and finish with the samples traced so far: outputs, encodings
  // and BakeResult::final_state as for any stopping rule (Termination::kStopped).
  const std::atomic<bool>* finish_now = nullptr;
  // Held around every iteration's device work. Bakes that share one device
  // (a daemon running several at once) pass the same mutex, so they take
  // turns on the device instead of oversubscribing it (two PoCL contexts on
  // one CPU would each start a thread per core).
  std::mutex* device_turn = nullptr;
  // BakeResult::final_state for a whole bake too (shards always get it):
  // a bake's accumulators as one "shard" of itself.
  bool keep_final_state = false;
};

Result<BakeResult> bake(const scene::Scene& scene, const BakeSettings& settings,
                        device::Context& ctx, const BakeHooks& hooks);

// The same wavefront over a probe domain (light probes, pipeline/probes/):
// each probe is a "texel" (i, 0) of a probes x 1 result whose domain is the
// whole sphere. `irradiance` holds each probe's scalar irradiance (the
// integral of radiance over the sphere, W/m^2; A = 1), `encodings` its SH
// radiance coefficients in the world frame (settings.encodings: sh1/sh2),
// `probe_visibility` its DDGI distance moments. Progress, error estimate,
// stop rules, snapshots, checkpoints and resume work as for lightmaps.
// INVALID_ARGUMENT for the Gaussian filter, adaptive sampling or a non-SH
// encoding.
Result<BakeResult> bake_probe_domain(const scene::Scene& scene, const BakeSettings& settings,
                                     const ProbeDomain& probes, device::Context& ctx,
                                     const BakeHooks& hooks = {});
Result<BakeResult> bake(const scene::Scene& scene, const BakeSettings& settings,
                        device::Context& ctx, const ProgressFn& on_progress = {});

}  // namespace luxel::pipeline
