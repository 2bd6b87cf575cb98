// What a bake is asked to do: lightmap size, stopping rules, light transport
// and ablation switches. The defaults, ranges, units and help of every field
// are in the settings schema (settings_schema.h); validate_settings() checks
// them and names the offending field, so the CLI and the service report the
// same errors.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "accel/intersector.h"
#include "atlas/atlas.h"
#include "bake/encodings.h"
#include "common/choices.h"
#include "common/status.h"
#include "shading/light_settings.h"

namespace luxel::pipeline {

// The settings' choices, each declared once with its names in the order
// the schema lists them (common/choices.h: choice_name, parse_choice,
// choice_list).

// Accumulation filter (kernels/bake/accumulate.h).
#define LUXEL_FILTER_CHOICES(X) X(kBox, "box") X(kGaussian, "gaussian")
LUXEL_CHOICE_ENUM(Filter, LUXEL_FILTER_CHOICES)

// Denoising of the finished lightmap (post/denoise.h, post/oidn.h): an extra
// output irradiance_denoised.exr; the raw irradiance.exr is always written
// too. kAuto is Open Image Denoise when its library loads and off otherwise
// (bake/baker_denoise.cpp; the rule and its measurements: docs/accuracy.md
// "Denoiser: the default").
#define LUXEL_DENOISE_CHOICES(X) \
  X(kOff, "off") X(kAtrous, "atrous") X(kOidn, "oidn") X(kAuto, "auto")
LUXEL_CHOICE_ENUM(Denoise, LUXEL_DENOISE_CHOICES)

// Direct light at the texel point (irradiance lightmaps): the exact
// unshadowed irradiance of analytic lights with sampled visibility
// (kernels/bake/raygen.h), or plain next-event estimation. kAuto takes the
// analytic form where it was measured to win: when every analytic light of
// the scene is punctual (bake/bake_features.cpp; docs/accuracy.md
// "Analytic direct light").
#define LUXEL_DIRECT_LIGHT_CHOICES(X) \
  X(kAuto, "auto") X(kAnalytic, "analytic") X(kSampled, "sampled")
LUXEL_CHOICE_ENUM(DirectLight, LUXEL_DIRECT_LIGHT_CHOICES)

// Where the lightmap UVs come from (bake/lightmap_layout.h).
#define LUXEL_UV_MODE_CHOICES(X) X(kAuto, "auto") X(kGenerate, "generate") X(kExisting, "existing")
LUXEL_CHOICE_ENUM(UvMode, LUXEL_UV_MODE_CHOICES)

// What target_error is compared with: the reference-free estimate (mean
// relative standard error), or, with a reference lightmap, RMSE or relMSE.
#define LUXEL_ERROR_METRIC_CHOICES(X) X(kEstimate, "estimate") X(kRmse, "rmse") X(kRelMse, "relmse")
LUXEL_CHOICE_ENUM(ErrorMetric, LUXEL_ERROR_METRIC_CHOICES)

// How the daemon runs and delivers a bake; not read by the engine. Part of
// BakeSettings so that one schema describes every setting of a SubmitBake.
#define LUXEL_SNAPSHOT_FORMAT_CHOICES(X) X(kPng, "png") X(kExr, "exr") X(kNone, "none")
LUXEL_CHOICE_ENUM(SnapshotFormat, LUXEL_SNAPSHOT_FORMAT_CHOICES)

struct JobSettings {
  int priority = 0;                // higher runs first; FIFO among equals
  double snapshot_interval_s = 5;  // seconds between snapshots
  SnapshotFormat snapshot_format = SnapshotFormat::kPng;
  int snapshot_max_side = 512;     // PNG snapshot longest side, pixels
  std::string reference_bake_id;   // benchmark mode on the daemon
  bool denoise_snapshots = false;  // snapshots denoised (with settings.denoise) for previews
  uint32_t shards = 0;             // coordinator mode: worker daemons to split across (0, 1: none)
  bool shards_auto = false;        // coordinator mode: one shard per resolved worker
};

// Lightmap placement of one glTF node dictated by the client (an editor
// plugin that owns the layout): what the node's extras.lightmapScaleOffset
// and lightmapIndex would say, given through the API so the file need not
// be rewritten. Overrides the node's extras; as with extras, either every
// baked instance ends up with a placement or none does.
struct NodePlacement {
  int node = -1;     // glTF node index
  int element = -1;  // EXT_mesh_gpu_instancing element; -1: the node's one instance
  float scale_offset[4] = {1, 1, 0, 0};  // atlas_uv = uv1 * (sx, sy) + (ox, oy), glTF UVs
  int page = 0;                          // lightmap page, [0, 1024)
};

struct BakeSettings {
  atlas::AtlasSettings atlas;                  // resolution or texel density
  std::vector<NodePlacement> node_placements;  // empty: the file's extras, or packed

  // Stopping rules: whichever is reached first. 0 disables a rule; at least
  // one must be set.
  // Paths per covered texel: with adaptive sampling the mean over covered
  // texels (paths traced = this x covered texels), uniform: every texel's.
  uint32_t samples_per_texel = 256;
  double time_budget_s = 0;  // wall-clock seconds of path tracing
  double target_error = 0;   // stop when target_metric falls to this
  ErrorMetric target_metric = ErrorMetric::kEstimate;
  // Benchmark mode: a reference lightmap of the bake's size, RGBA float per
  // texel, row 0 = top (as BakeResult::irradiance, e.g. a converged bake's
  // irradiance.exr). Every progress report then carries RMSE and relMSE
  // against it (DESIGN.md "Accuracy and error reporting").
  std::shared_ptr<const std::vector<float>> reference;
  std::string reference_name;  // where it came from (manifest, logs)

  int max_bounces = 4;  // indirect bounces after the texel point (0 = direct light only)
  int rr_depth = 3;     // Russian roulette from this vertex depth on
  // Batch size: bounds device memory. 0: auto, the device's batch
  // (resource_estimate.h, batch_paths_request).
  uint32_t paths_per_iteration = 0;
  // Device memory the bake may hold, MiB; past it (or past the device's
  // largest allocation) the atlas is baked in tiles (bake/tile_plan.h).
  // 0: min(80 % of the device's memory, 4 GiB).
  double device_memory_budget_mib = 0;
  uint32_t seed = 1;
  Filter filter = Filter::kBox;
  DirectLight direct = DirectLight::kAuto;  // docs/accuracy.md "Analytic direct light"
  // Ray queries: Embree on the host for CPU devices, the OpenCL traversal
  // for GPUs (auto), or either on request (accel/intersector.h).
  accel::IntersectorKind intersector = accel::IntersectorKind::kAuto;
  // Lightmap UVs: TEXCOORD_1 when every baked mesh has valid ones (auto),
  // always generated, or always the file's (bake/lightmap_layout.h).
  UvMode uv = UvMode::kAuto;
  float clamp_luminance = 0;   // firefly clamp on a path's luminance; 0 = off (unbiased)
  LightSettings lights;        // sky, sun, directional angular radius
  EncodingSettings encodings;  // directional encodings besides irradiance

  // Adaptive sampling (thesis §3.3, kernels/bake/adaptive.h): after a
  // uniform warm-up of adaptive_min_samples paths per texel, each
  // iteration's paths go to texels in proportion to their relative error.
  bool adaptive = true;
  uint32_t adaptive_min_samples = 8;

  // The radiance cache (kernels/bake/radiance_cache.h): first hits on
  // lightmapped diffuse surfaces gather from the cached irradiance of their
  // texel instead of tracing on, with a share that falls as n^-1/2 so the
  // bake stays consistent. On by default (docs/performance.md "Radiance
  // cache and first-bounce guiding"); off in sharded bakes and probe bakes.
  bool radiance_cache = true;
  // First-bounce guiding (kernels/bake/guiding.h): each texel's first
  // direction comes from a one-sample mixture of the cosine lobe and a
  // histogram learned from its earlier paths. Irradiance lightmaps only
  // (no directional encodings, no probes).
  bool guiding = false;

  // Distributed bakes (shards/shard_merge.h): this bake is shard
  // shard_index of shard_count and traces only its part of every texel's
  // sample sequence (kernels/shared/shard.h); samples_per_texel stays the
  // whole bake's count, of which the shard traces shard_samples(). 0 or 1:
  // the whole bake. Sharded bakes sample uniformly (adaptive off), use the
  // box filter and fit directional encodings by projection, so that the
  // shards' accumulators merge exactly.
  uint32_t shard_index = 0;
  uint32_t shard_count = 1;
  bool sharded() const { return shard_count > 1; }
  // The samples per texel this bake traces: samples_per_texel, or a shard's
  // part of it (kernels/shared/shard.h). 0: no sample rule.
  uint32_t shard_samples() const;

  // Ablation switches (thesis §5.1, §5.4, §6.2).
  bool compaction = true;
  bool sort_directions = false;
  bool random_sequence = false;

  double progress_interval_s = 1.0;  // progress callback period
  int dilation_texels = 2;           // output: fill uncovered texels this far
  Denoise denoise = Denoise::kAuto;  // output: irradiance_denoised.exr besides irradiance.exr
  bool seam_stitch = true;           // output: make texels agree across UV seams (seam_stitch.h)
  JobSettings job;                   // daemon only

  // Light probes (server/engine/probes/): "" = none, else the placement of
  // settings/probe_spec.h ("grid:0.5", "grid:0.5:box=...", "file:P.json",
  // "adaptive:0.5"), baked after the lightmap in the same job.
  std::string probes;
  std::string probe_positions;           // file mode: the JSON list (the CLI reads the file)
  int probe_sh_order = 2;                // 1: L1 (4 coefficients), 2: L2 (9)
  std::string probe_window = "hanning";  // ringing control at evaluation: none, hanning, lanczos
  bool lightmap = true;                  // false: the job bakes probes only

  // The settings as "key=value" strings, for manifests and reports.
  std::map<std::string, std::string> describe() const;
};

// INVALID_ARGUMENT naming the field ("settings.max_bounces: must be in [0, 64], got 99"):
// every active setting's schema rule, then the rules between settings.
// `resolution_limit` names where atlas.resolution_limit comes from in errors.
Status validate_settings(const BakeSettings& settings,
                         const char* resolution_limit = "the engine's largest lightmap side");

}  // namespace luxel::pipeline
