// `luxel bake SCENE --local --out DIR ...`: runs the bake engine in-process
// with a progress bar and writes the lightmap, preview, maps and manifest.
// Without --local the same command line goes to luxeld (remote/bake_remote.cpp).
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "api/scene_files.h"
#include "bake/host_memory.h"
#include "bake/resource_estimate.h"
#include "bake_options.h"
#include "commands.h"
#include "device/context.h"
#include "job/bake_job.h"
#include "output/reference_exr.h"
#include "probes/sh_window.h"
#include "progress_bar.h"
#include "scene/gltf_import.h"
#include "settings/fingerprint.h"
#include "settings/probe_spec.h"

namespace luxel::cli {
namespace {

void draw_progress(const pipeline::BakeProgress& p, bool tty) {
  ProgressView v;
  v.fraction = p.fraction;
  v.mean_spp = p.mean_spp;
  v.min_spp = p.min_spp;
  v.error = p.error;
  v.elapsed_s = p.elapsed_s;
  v.eta_s = p.eta_s;
  v.rmse = p.rmse;
  v.rel_mse = p.rel_mse;
  draw_progress_bar(v, tty);
}

// The lightmap's figures, as soon as its bake ends (before the probes).
void print_lightmap(const BakeCommand& a, const pipeline::BakeResult& r) {
  std::printf("lightmap   %dx%d (%s atlas), %zu covered texels, sample-info buffer %.1f MiB\n",
              r.width, r.height, atlas::atlas_mode_name(r.atlas.mode), r.covered_texels,
              r.sample_info_bytes / 1048576.0);
  std::printf("features   %s\n", r.features.c_str());
  std::printf("intersector %s\n", r.intersector.c_str());
  std::printf(
      "baked      %.2f s (+%.2f s setup), %llu paths (%.2f Mpaths/s), spp mean %.1f min %u, "
      "error %.4f, stopped by %s\n",
      r.seconds, r.setup_s, static_cast<unsigned long long>(r.paths),
      r.seconds > 0 ? r.paths / r.seconds / 1e6 : 0.0, r.mean_spp, r.min_spp, r.error,
      pipeline::termination_name(r.termination));
  if (r.rmse >= 0)
    std::printf("reference  rmse %.5g, relMSE %.5g against %s\n", r.rmse, r.rel_mse,
                a.settings.reference_name.c_str());
  if (r.nonfinite_dropped > 0)
    std::printf("warning    %llu non-finite samples dropped\n",
                static_cast<unsigned long long>(r.nonfinite_dropped));
  std::printf("memory     %.1f MiB on the device (budget %.0f MiB, %zu tile%s)\n",
              r.peak_device_bytes / 1048576.0, r.device_memory_budget / 1048576.0, r.tiles,
              r.tiles == 1 ? "" : "s");
  for (const auto& e : r.encodings)
    std::printf("encoding   %-15s %2d coefficients x RGB, %s\n", e.name.c_str(), e.count,
                e.residual_rms >= 0 ? strprintf("running residual %.4g", e.residual_rms).c_str()
                                    : "projection");
  if (!r.encodings.empty())
    std::printf("           basis state %zu bytes per texel on the device\n",
                r.basis_bytes_per_texel);
  std::printf("\nkernel timings (OpenCL profiling events)\n%s", r.kernel_table.c_str());
}

void print_probe_layout(const probes::ProbeLayout& l, const std::string& spec) {
  std::printf(
      "probes     %zu (%s), %zu inside geometry: %zu moved out, %zu flagged%s\n",
      l.positions.size(), spec.c_str(), l.inside_detected, l.moved, l.flagged_inside,
      l.dropped_far ? strprintf(", %zu far from geometry dropped", l.dropped_far).c_str() : "");
}

void print_probes(const probes::ProbeBake& b) {
  const pipeline::BakeResult& r = b.bake;
  std::printf(
      "probes     %.2f s, %llu paths (%.3f M probe-samples/s), samples per probe mean %.1f min "
      "%u, error %.4f, stopped by %s\n",
      r.seconds, static_cast<unsigned long long>(r.paths),
      r.seconds > 0 ? r.paths / r.seconds / 1e6 : 0.0, r.mean_spp, r.min_spp, r.error,
      pipeline::termination_name(r.termination));
  std::printf("           negative irradiance: raw %.4f, %s %.4f of (probe, normal) pairs\n",
              b.negative_raw, probes::sh_window_name(b.window), b.negative_windowed);
}

void print_written(const BakeCommand& a, const job::JobResult& job) {
  const pipeline::OutputPaths& w = job.written;
  if (job.lightmap) {
    std::printf("\nwrote      %s\n           %s\n           %s\n", w.irradiance_exr.c_str(),
                w.preview_png.c_str(), w.manifest_json.c_str());
    if (!w.irradiance_denoised_exr.empty())
      std::printf("           %s (denoised, %.2f s)\n", w.irradiance_denoised_exr.c_str(),
                  job.lightmap->denoise_s);
    for (const auto& f : w.encodings) std::printf("           %s\n", f.c_str());
    if (!w.lightmapped_glb.empty()) std::printf("           %s\n", w.lightmapped_glb.c_str());
  }
  if (job.probes)
    std::printf("wrote      %s/probes.bin\n           %s/probes.json\n", a.out.c_str(),
                a.out.c_str());
}

}  // namespace

int run_bake(const std::vector<std::string>& args) {
  BakeCommand a;
  switch (parse_bake_args(args, a)) {
    case ParseOutcome::kHelpShown:
      return 0;
    case ParseOutcome::kUsageError:
      return 2;
    case ParseOutcome::kOk:
      break;
  }
  if (!a.local) return run_bake_remote(a);
  if (!a.remote_only.empty()) {
    std::fprintf(stderr, "luxel bake: %s applies to a bake on luxeld, not to --local\n",
                 a.remote_only.front().c_str());
    return 2;
  }
  if (!read_probe_positions(a)) return 2;
  if (const std::string& file = a.settings.reference_name; !file.empty()) {
    // Benchmark mode: RGBA (or RGB) float EXR of the lightmap's size.
    auto image = output::read_reference_exr(file);
    if (!image) {
      std::fprintf(stderr, "luxel bake: --reference: %s\n", image.status().to_string().c_str());
      return 1;
    }
    a.settings.reference = std::make_shared<const std::vector<float>>(std::move(image->pixels));
  }
  if (auto st = pipeline::validate_settings(a.settings); !st.is_ok()) {
    std::fprintf(stderr, "luxel bake: %s\n", st.message().c_str());
    return 2;
  }
  auto scene = scene::import_gltf_file(a.scene);
  if (!scene) {
    std::fprintf(stderr, "luxel bake: %s\n", scene.status().to_string().c_str());
    return 1;
  }
  auto ctx = device::Context::create(a.device);
  if (!ctx) {
    std::fprintf(stderr, "luxel bake: %s\n", ctx.status().to_string().c_str());
    return 1;
  }
  // Named as luxeld names an upload by default (its file name), so a local
  // bake writes the same bytes as the daemon's. The daemon's check at
  // SubmitBake (job::check_bake_job): a bake that
  // cannot fit, or probes that cannot be placed, are refused before the
  // layout and the BVH are built.
  job::JobInput input{.scene = &scene.value(),
                      .settings = a.settings,
                      .scene_file = a.scene,
                      .scene_name = std::filesystem::path(a.scene).filename().string()};
  // The host side too (bake/host_memory.h): on a CPU device the device
  // buffers are host memory. A local bake writes no checkpoints.
  const auto device = pipeline::DeviceLimits::of(ctx.value()->info());
  const job::HostMemoryCheck host{.budget = a.host_memory_budget < 0
                                                ? pipeline::default_host_memory_budget()
                                                : static_cast<size_t>(a.host_memory_budget),
                                  .device_is_host = !device.is_gpu,
                                  .checkpoints = false,
                                  .budget_name = "luxel bake --host-memory-budget"};
  pipeline::HostMemoryEstimate host_estimate;
  if (Status st = job::check_bake_job(input, device, host, &host_estimate); !st.is_ok()) {
    std::fprintf(stderr, "luxel bake: %s\n", st.to_string().c_str());
    return st.code() == StatusCode::kInvalidArgument ? 2 : 1;
  }
  std::printf("scene      %s\ndevice     %s\n", a.scene.c_str(),
              ctx.value()->info().describe().c_str());
  if (a.settings.lightmap && !a.quiet)
    std::printf("host mem   estimated %zu bytes (%s), budget %zu\n", host_estimate.total(),
                host_estimate.describe().c_str(), host.budget);
  const bool tty = isatty(fileno(stdout));
  const bool bar = tty && !a.quiet;
  job::JobEvents events;
  if (a.settings.sharded()) {
    // A shard's accumulators.bin carries the bake's fingerprint, as the
    // daemon derives it (scene id + settings without the shard), so shards
    // baked here and on daemons merge (shards/shard_merge.h).
    remote::SceneFiles files;
    if (remote::collect_scene_files(a.scene, files).ok())
      events.hooks.fingerprint = pipeline::bake_fingerprint(remote::scene_id(files), a.settings);
  }
  events.hooks.on_layout = [](const std::string& line) {
    std::printf("uv         %s\n", line.c_str());
    std::fflush(stdout);
  };
  events.hooks.on_progress = [&](const pipeline::BakeProgress& p) {
    if (!a.quiet) draw_progress(p, tty);
    return true;
  };
  events.on_lightmap = [&](const pipeline::BakeResult& r) {
    if (bar) std::printf("\n");
    print_lightmap(a, r);
  };
  events.on_probe_layout = [&](const probes::ProbeLayout& l) {
    print_probe_layout(
        l, probes::describe_probe_spec(probes::parse_probe_spec(a.settings.probes).value()));
  };
  events.on_probes = [&](const probes::ProbeBake& b) {
    if (bar) std::printf("\n");
    print_probes(b);
  };
  auto job = job::run_bake_job(input, *ctx.value(), events, a.out);
  if (!job) {
    if (bar) std::printf("\n");
    std::fprintf(stderr, "luxel bake: %s\n", job.status().to_string().c_str());
    return job.status().code() == StatusCode::kInvalidArgument ? 2 : 1;
  }
  print_written(a, job.value());
  return 0;
}

}  // namespace luxel::cli
