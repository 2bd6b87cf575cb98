// `luxel bake SCENE --local --out DIR ...`: runs the bake engine in-process
// with a progress bar and writes the lightmap, preview, maps and manifest.
// Without --local the same command line goes to luxeld (remote/bake_remote.cpp).
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "api/scene_files.h"
#include "api/settings_translate.h"
#include "bake/bake.h"
#include "bake/resource_estimate.h"
#include "bake_options.h"
#include "commands.h"
#include "device/context.h"
#include "output/reference_exr.h"
#include "post/bake_outputs.h"
#include "probes/gltf_nodes.h"
#include "probes/probe_bake.h"
#include "probes/probe_file.h"
#include "progress_bar.h"
#include "scene/gltf_import.h"
#include "settings/fingerprint.h"

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

}  // namespace

// The lightmap of the bake: outputs and the report.
static int run_lightmap(const BakeArgs& a, const scene::Scene& scene, device::Context& ctx,
                        const pipeline::BakeHooks& hooks, bool tty) {
  auto result = pipeline::bake(scene, a.settings, ctx, hooks);
  if (tty && !a.quiet) std::printf("\n");
  if (!result) {
    std::fprintf(stderr, "luxel bake: %s\n", result.status().to_string().c_str());
    return 1;
  }
  const auto& r = result.value();
  auto paths = pipeline::write_bake_outputs(a.out, scene, a.settings, r, "", a.scene);
  if (!paths) {
    std::fprintf(stderr, "luxel bake: %s\n", paths.status().to_string().c_str());
    return 1;
  }
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
  std::printf("\nwrote      %s\n           %s\n           %s\n",
              paths.value().irradiance_exr.c_str(), paths.value().preview_png.c_str(),
              paths.value().manifest_json.c_str());
  if (!paths.value().irradiance_denoised_exr.empty())
    std::printf("           %s (denoised, %.2f s)\n", paths.value().irradiance_denoised_exr.c_str(),
                r.denoise_s);
  for (const auto& f : paths.value().encodings) std::printf("           %s\n", f.c_str());
  if (!paths.value().lightmapped_glb.empty())
    std::printf("           %s\n", paths.value().lightmapped_glb.c_str());
  return 0;
}

// The light probes of the bake (server/engine/probes/): placement, the
// probe-domain bake, probes.bin and probes.json in --out.
static int run_probes(const BakeArgs& a, const scene::Scene& scene, device::Context& ctx,
                      const pipeline::BakeHooks& hooks, bool tty) {
  auto spec = probes::parse_probe_spec(a.settings.probes);
  if (!spec) {
    std::fprintf(stderr, "luxel bake: %s\n", spec.status().message().c_str());
    return 2;
  }
  probes::ProbeBakeSettings ps;
  ps.placement = spec.value();
  if (ps.placement.mode == probes::PlacementMode::kFile) {
    std::ifstream f(ps.placement.file, std::ios::binary);
    std::stringstream text;
    text << f.rdbuf();
    if (!f) {
      std::fprintf(stderr, "luxel bake: --probes: cannot read %s\n", ps.placement.file.c_str());
      return 1;
    }
    ps.placement.file_contents = text.str();
  }
  if (ps.placement.mode == probes::PlacementMode::kNodes) {
    std::ifstream f(a.scene, std::ios::binary);
    std::stringstream bytes;
    bytes << f.rdbuf();
    auto nodes = probes::probe_nodes_json(bytes.str());
    if (!nodes) {
      std::fprintf(stderr, "luxel bake: %s\n", nodes.status().message().c_str());
      return 2;
    }
    ps.placement.file_contents = nodes.value();
  }
  ps.basis = a.settings.probe_sh_order == 1 ? "sh1" : "sh2";
  ps.window = probes::parse_sh_window(a.settings.probe_window).value();
  auto layout = probes::place_probes(scene, ps.placement);
  if (!layout) {
    std::fprintf(stderr, "luxel bake: %s\n", layout.status().to_string().c_str());
    return 1;
  }
  const probes::ProbeLayout& l = layout.value();
  std::printf(
      "probes     %zu (%s), %zu inside geometry: %zu moved out, %zu flagged%s\n",
      l.positions.size(), probes::describe_probe_spec(ps.placement).c_str(), l.inside_detected,
      l.moved, l.flagged_inside,
      l.dropped_far ? strprintf(", %zu far from geometry dropped", l.dropped_far).c_str() : "");
  auto result = probes::bake_probe_layout(scene, a.settings, ps, layout.value(), ctx, hooks);
  if (tty && !a.quiet) std::printf("\n");
  if (!result) {
    std::fprintf(stderr, "luxel bake: probes: %s\n", result.status().to_string().c_str());
    return 1;
  }
  const probes::ProbeBake& b = result.value();
  const pipeline::BakeResult& r = b.bake;
  std::printf(
      "probes     %.2f s, %llu paths (%.3f M probe-samples/s), samples per probe mean %.1f min "
      "%u, error %.4f, stopped by %s\n",
      r.seconds, static_cast<unsigned long long>(r.paths),
      r.seconds > 0 ? r.paths / r.seconds / 1e6 : 0.0, r.mean_spp, r.min_spp, r.error,
      pipeline::termination_name(r.termination));
  std::printf("           negative irradiance: raw %.4f, %s %.4f of (probe, normal) pairs\n",
              b.negative_raw, probes::sh_window_name(b.window), b.negative_windowed);
  if (auto st = probes::write_probe_files(b, a.out); !st.is_ok()) {
    std::fprintf(stderr, "luxel bake: %s\n", st.to_string().c_str());
    return 1;
  }
  std::printf("wrote      %s/probes.bin\n           %s/probes.json\n", a.out.c_str(),
              a.out.c_str());
  return 0;
}

int run_bake(const std::vector<std::string>& args) {
  BakeArgs a;
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
  // The daemon's check at SubmitBake (bake/resource_estimate.h): a bake
  // that cannot fit is refused before the layout and the BVH are built.
  if (a.settings.lightmap)
    if (auto e = pipeline::estimate_bake_resources(scene.value(), a.settings,
                                                   pipeline::DeviceLimits::of(ctx.value()->info()));
        !e) {
      std::fprintf(stderr, "luxel bake: %s\n", e.status().to_string().c_str());
      return 1;
    }
  std::printf("scene      %s\ndevice     %s\n", a.scene.c_str(),
              ctx.value()->info().describe().c_str());
  const bool tty = isatty(fileno(stdout));
  pipeline::BakeHooks hooks;
  if (a.settings.sharded()) {
    // A shard's accumulators.bin carries the bake's fingerprint, as the
    // daemon derives it (scene id + settings without the shard), so shards
    // baked here and on daemons merge (shards/shard_merge.h).
    remote::SceneFiles files;
    if (remote::collect_scene_files(a.scene, files).ok())
      hooks.fingerprint = pipeline::bake_fingerprint(remote::scene_id(files), a.settings);
  }
  hooks.on_layout = [](const std::string& line) {
    std::printf("uv         %s\n", line.c_str());
    std::fflush(stdout);
  };
  hooks.on_progress = [&](const pipeline::BakeProgress& p) {
    if (!a.quiet) draw_progress(p, tty);
    return true;
  };
  if (a.settings.lightmap)
    if (int rc = run_lightmap(a, scene.value(), *ctx.value(), hooks, tty)) return rc;
  if (!a.settings.probes.empty()) return run_probes(a, scene.value(), *ctx.value(), hooks, tty);
  return 0;
}

}  // namespace luxel::cli
