#include "job/bake_job.h"

#include <filesystem>

#include "bake/bake_setup.h"
#include "bake/lightmap_layout.h"
#include "common/atomic_file.h"
#include "probes/gltf_nodes.h"
#include "probes/placement.h"
#include "probes/probe_file.h"
#include "probes/sh_window.h"
#include "settings/probe_spec.h"

namespace luxel::job {
namespace {

using pipeline::BakeResult;
using pipeline::Termination;

// The probe bake's settings from the bake settings: placement, basis and
// window, with the positions or nodes the placement reads.
Result<probes::ProbeBakeSettings> probe_settings(const JobInput& in) {
  const pipeline::BakeSettings& s = in.settings;
  auto spec = probes::parse_probe_spec(s.probes);
  if (!spec) return spec.status();
  probes::ProbeBakeSettings ps;
  ps.placement = spec.value();
  ps.placement.file_contents = s.probe_positions;
  if (ps.placement.mode == probes::PlacementMode::kNodes) {
    auto file = read_whole_file(in.scene_file);
    if (!file) return file.status();
    auto nodes = probes::probe_nodes_json(file.value());
    if (!nodes) return nodes.status();
    ps.placement.file_contents = nodes.value();
  }
  ps.basis = s.probe_sh_order == 1 ? "sh1" : "sh2";
  auto window = probes::parse_sh_window(s.probe_window);
  if (!window) return window.status();
  ps.window = window.value();
  return ps;
}

// A fixed resolution of at most kSmallLayoutSide texels is laid out at
// submit (lay_out_lightmap, as the bake does): charts that fit no page, or
// an instanced mesh whose own layout outgrows the page, are refused before
// the job is queued. The layout costs what charting the scene costs: 1.9 s
// for the 550k triangles of procedural_city.glb on 2 cores, so scenes past
// kSmallLayoutTriangles are left to the bake.
constexpr int kSmallLayoutSide = 256;
constexpr size_t kSmallLayoutTriangles = 1000000;

Status check_small_layout(const JobInput& in) {
  const pipeline::BakeSettings& s = in.settings;
  if (s.atlas.resolution <= 0 || s.atlas.resolution > kSmallLayoutSide) return Status::ok();
  size_t triangles = 0;
  for (const scene::Instance& inst : in.scene->instances)
    if (inst.mesh >= 0 && static_cast<size_t>(inst.mesh) < in.scene->meshes.size())
      triangles += in.scene->meshes[static_cast<size_t>(inst.mesh)].indices.size() / 3;
  if (triangles == 0 || triangles > kSmallLayoutTriangles) return Status::ok();
  auto layout = pipeline::lay_out_lightmap(*in.scene, s);
  Status st = layout.status();
  if (layout) {
    // The bake's first step on the layout (prepare_bake): a lightmap where
    // no texel holds a sample of any triangle.
    auto info = pipeline::covered_sample_info(*layout->scene, layout->atlas);
    if (info) return Status::ok();
    st = info.status();
  }
  if (st.message().rfind("settings.", 0) == 0) return st;
  return Status(st.code(),
                strprintf("settings.resolution: %d: %s", s.atlas.resolution, st.message().c_str()));
}

// The name the user knows the scene by: the job's, the file's, the scene's own.
std::string scene_label(const JobInput& in) {
  if (!in.scene_name.empty()) return in.scene_name;
  if (!in.scene_file.empty()) return std::filesystem::path(in.scene_file).filename().string();
  return in.scene->source_name;
}

Result<BakeResult> bake_lightmap(const JobInput& in, device::Context& ctx, const JobEvents& ev) {
  auto r =
      ev.bake_lightmap ? ev.bake_lightmap() : pipeline::bake(*in.scene, in.settings, ctx, ev.hooks);
  // Refusals of the scene as laid out (no triangles, charts that fit no
  // page, bad TEXCOORD_1) name the file here, the one place that knows it,
  // so that the CLI and the daemon say which scene of a batch was refused.
  const StatusCode code = r.status().code();
  if (!r && (code == StatusCode::kInvalidArgument || code == StatusCode::kResourceExhausted))
    return Status(code, "scene '" + scene_label(in) + "': " + r.status().message());
  if (r && ev.on_lightmap) ev.on_lightmap(r.value());
  return r;
}

Result<probes::ProbeBake> bake_probes(const JobInput& in, device::Context& ctx, const JobEvents& ev,
                                      bool after_lightmap) {
  auto ps = probe_settings(in);
  if (!ps) return ps.status();
  auto layout = probes::place_probes(*in.scene, ps.value().placement, CancelToken(ev.hooks.cancel));
  if (!layout) return layout.status();
  if (ev.on_probe_layout) ev.on_probe_layout(layout.value());
  pipeline::BakeHooks hooks = ev.hooks;
  hooks.on_snapshot = nullptr;  // a probe set is no image
  hooks.snapshot_interval_s = 0;
  if (after_lightmap) {
    hooks.resume = nullptr;
    hooks.on_checkpoint = nullptr;
    hooks.checkpoint_interval_s = 0;
    hooks.checkpoint_now = nullptr;
  }
  auto b = probes::bake_probe_layout(*in.scene, in.settings, ps.value(), std::move(layout.value()),
                                     ctx, hooks);
  if (b && ev.on_probes) ev.on_probes(b.value());
  return b;
}

Status write_outputs(const JobInput& in, const std::string& dir, JobResult& job) {
  if (job.lightmap) {
    // The job is done with the images once they are written (its caller
    // reads the figures): each is released as its file is written.
    auto written = pipeline::write_bake_outputs_releasing(
        dir, *in.scene, in.settings, *job.lightmap, in.scene_sha256, in.scene_file, in.scene_name);
    if (!written) return written.status();
    job.written = std::move(written.value());
  } else {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) return internal_error("cannot create " + dir + ": " + ec.message());
  }
  if (job.probes) {
    LUXEL_RETURN_IF_ERROR(probes::write_probe_files(*job.probes, dir));
    job.written.files.push_back("probes.bin");
    job.written.files.push_back("probes.json");
  }
  return Status::ok();
}

}  // namespace

Status check_bake_job(const JobInput& in, const pipeline::DeviceLimits& device,
                      const HostMemoryCheck& host, pipeline::HostMemoryEstimate* estimate) {
  const pipeline::BakeSettings& s = in.settings;
  if (s.lightmap) {
    auto e = pipeline::estimate_bake_resources(*in.scene, s, device);
    if (!e) return e.status();
    if (host.budget > 0 || estimate) {
      auto h = pipeline::estimate_host_memory(e.value(), s, host.device_is_host, host.checkpoints);
      if (!h) return h.status();
      if (estimate) *estimate = h.value();
      LUXEL_RETURN_IF_ERROR(
          pipeline::check_host_memory(h.value(), s, host.budget, host.budget_name));
    }
    LUXEL_RETURN_IF_ERROR(check_small_layout(in));
  }
  if (!s.probes.empty()) {
    auto ps = probe_settings(in);
    if (!ps) return ps.status();
    auto plan = probes::plan_placement(*in.scene, ps.value().placement);
    if (!plan) return plan.status();
  }
  return Status::ok();
}

bool JobResult::cancelled() const {
  return (lightmap && lightmap->termination == Termination::kCancelled) ||
         (probes && probes->bake.termination == Termination::kCancelled);
}

const BakeResult& JobResult::figures() const {
  return lightmap ? *lightmap : probes->bake;
}

Result<JobResult> run_bake_job(const JobInput& in, device::Context& ctx, const JobEvents& events,
                               const std::string& out_dir) {
  JobResult job;
  if (in.settings.lightmap) {
    auto r = bake_lightmap(in, ctx, events);
    if (!r) return r.status();
    job.lightmap = std::move(r.value());
    if (job.cancelled()) return job;
  }
  // A cancel after the lightmap's last iteration (or during the probes'
  // last) ends the job here, before the next step or the outputs.
  const CancelToken cancel(events.hooks.cancel);
  auto cancelled_now = [&]() -> JobResult {
    pipeline::BakeResult& r = job.lightmap ? *job.lightmap : job.probes->bake;
    r.termination = Termination::kCancelled;
    return std::move(job);
  };
  if (job.lightmap && cancel.requested()) return cancelled_now();
  if (!in.settings.probes.empty()) {
    auto b = bake_probes(in, ctx, events, job.lightmap.has_value());
    if (!b) return b.status();
    job.probes = std::move(b.value());
    if (job.cancelled()) return job;
  }
  if (!job.lightmap && !job.probes)
    return invalid_argument(
        "settings.lightmap: off, and settings.probes is empty: nothing to bake");
  if (cancel.requested()) return cancelled_now();
  LUXEL_RETURN_IF_ERROR(write_outputs(in, out_dir, job));
  return job;
}

}  // namespace luxel::job
