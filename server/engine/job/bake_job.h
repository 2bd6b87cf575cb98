// One bake job, the only caller of the bake for the CLI's `--local` mode and
// for the daemon:
//
//   lay out and bake the lightmap (bake/bake.h: layout, samples, denoise,
//   stitched seams)  ->  place and bake the light probes (probes/)  ->
//   write the outputs (post/bake_outputs.h, probes/probe_file.h)
//
// The front ends import and validate at their edge (the CLI's flags, the
// daemon's SubmitBake and scene store), then only turn the job's events into
// a progress bar or into gRPC records, snapshots and checkpoints. Which steps
// run follows the settings: `lightmap` off bakes probes alone, `probes`
// empty bakes no probes.
#pragma once

#include <functional>
#include <optional>
#include <string>

#include "bake/bake.h"
#include "bake/host_memory.h"
#include "bake/resource_estimate.h"
#include "common/status.h"
#include "device/context.h"
#include "post/bake_outputs.h"
#include "probes/probe_bake.h"
#include "scene/scene.h"
#include "settings/bake_settings.h"

namespace luxel::job {

// What a job bakes. The scene is imported and the settings validated by the
// caller (settings.reference loaded, settings.probe_positions holding the
// file's text for `probes = file:...`).
struct JobInput {
  const scene::Scene* scene = nullptr;
  pipeline::BakeSettings settings;
  // The scene's main glTF file: `probes = nodes` reads its tagged nodes, and
  // the lightmapped glTF (generated UVs) is written from it.
  std::string scene_file;
  std::string scene_sha256;  // the scene id for the manifest; may be empty
  std::string scene_name;    // the name the user knows it by; empty: the scene's own
};

// What the front end hears, and how it steers the job.
struct JobEvents {
  // Progress, layout, snapshots, checkpoints, resume, cancel and finish of
  // the lightmap bake. The probe bake gets the same hooks without snapshots
  // (a probe set is no image) and, after a lightmap, without checkpoints or
  // resume (a restart redoes the probes after the lightmap's last
  // checkpoint).
  pipeline::BakeHooks hooks;
  // Bakes the lightmap in place of bake() (the daemon's coordinator, which
  // shards it across workers); null: bake() on `ctx`.
  std::function<Result<pipeline::BakeResult>()> bake_lightmap;
  // Each step's result as soon as it is known.
  std::function<void(const pipeline::BakeResult&)> on_lightmap;
  std::function<void(const probes::ProbeLayout&)> on_probe_layout;  // before the probe bake
  std::function<void(const probes::ProbeBake&)> on_probes;
};

struct JobResult {
  // Once the outputs are written, a one-page lightmap's images are released
  // (post/bake_outputs.h, write_bake_outputs_releasing); its figures stay.
  std::optional<pipeline::BakeResult> lightmap;
  std::optional<probes::ProbeBake> probes;
  // Files written into the output folder (the lightmap's, then probes.bin
  // and probes.json); nothing is written for a cancelled job.
  pipeline::OutputPaths written;

  bool cancelled() const;
  // The job's figures: the lightmap's, or the probes' when there is none.
  const pipeline::BakeResult& figures() const;
};

// What the job can refuse before it runs, checked with the functions the
// run uses, so that a job accepted here does not FAIL for a reason known
// now: the lightmap's resources against `device` (bake/resource_estimate.h),
// a small fixed resolution laid out as the bake lays it out (charts that fit
// no page), and the probe placement (probes::plan_placement: the grid's
// count, the file's or the glTF nodes' positions). The daemon runs it at
// SubmitBake and the CLI before `bake --local`. Errors start with the
// setting ("settings.probes: ...").
//
// With a host-memory budget, the lightmap's host peak too
// (bake/host_memory.h), refused over it with RESOURCE_EXHAUSTED naming the
// settings and the bytes; `estimate`, when given, receives it.
struct HostMemoryCheck {
  size_t budget = 0;            // bytes; 0: not checked
  bool device_is_host = false;  // a CPU device: its buffers are host memory
  bool checkpoints = false;     // the host writes checkpoints (keeps finished tiles)
  std::string budget_name;      // the flag that sets it, for the message
};
Status check_bake_job(const JobInput& input, const pipeline::DeviceLimits& device,
                      const HostMemoryCheck& host = {},
                      pipeline::HostMemoryEstimate* estimate = nullptr);

// Runs the job on `ctx` and writes its outputs into `out_dir` (created if
// needed). A cancelled step (hooks.cancel) ends the job with what it has and
// writes nothing; one cancelled during its setup fails with cancelled_error
// (common/cancel.h), which the host that set the flag reads as cancelled.
// Errors name the step (and the setting or file) at fault;
// the lightmap's INVALID_ARGUMENT and RESOURCE_EXHAUSTED start with "scene
// 'NAME': " (scene_name, else the file name).
Result<JobResult> run_bake_job(const JobInput& input, device::Context& ctx, const JobEvents& events,
                               const std::string& out_dir);

}  // namespace luxel::job
