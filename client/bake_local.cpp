// `luxel bake SCENE --local --out DIR ...`: runs the bake engine in-process
// with a progress bar and writes the lightmap, preview, maps and manifest.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "commands.h"
#include "device/context.h"
#include "pipeline/bake.h"
#include "pipeline/bake_outputs.h"
#include "scene/gltf_import.h"

namespace luxel::cli {
namespace {

struct BakeArgs {
  std::string scene, out, device;
  bool local = false;
  bool quiet = false;
  pipeline::BakeSettings settings;
};

const char* kUsage =
    "usage: luxel bake SCENE --local --out DIR [options]\n"
    "  --samples N           samples per texel to reach (default 256; 0 = no sample limit)\n"
    "  --time SECONDS        time budget for path tracing\n"
    "  --target-error E      stop at this mean relative standard error (e.g. 0.02)\n"
    "  --bounces B           indirect bounces (default 4; 0 = direct light only)\n"
    "  --resolution N        lightmap side in texels (default 512)\n"
    "  --texel-density D     texels per world unit (instead of --resolution)\n"
    "  --seed S              random seed (same seed, same result)\n"
    "  --filter box|gaussian accumulation filter (default box)\n"
    "  --sky R,G,B           constant sky radiance\n"
    "  --sky-image FILE      equirectangular HDR/EXR sky  [--sky-intensity X] [--sky-rotation DEG]\n"
    "  --sun X,Y,Z           sun travelling along X,Y,Z  [--sun-illuminance E] [--sun-radius DEG]\n"
    "  --directional-radius DEG  angular radius of the scene's directional lights\n"
    "  --paths-per-iteration N   batch size (default 262144)\n"
    "  --rr-depth D          Russian roulette from this depth (default 3)\n"
    "  --clamp L             clamp path luminance (biased; default off)\n"
    "  --no-compaction, --sort-directions, --random-sequence   ablation switches\n"
    "  --dilate N            dilate uncovered texels by N (default 2)\n"
    "  --progress-interval S seconds between progress updates (default 1)\n"
    "  --device SPEC         OpenCL device (see `luxel devices`)\n"
    "  --quiet               no progress bar\n";

bool parse_vec3(const std::string& s, Vec3& v) {
  return std::sscanf(s.c_str(), "%f,%f,%f", &v.x, &v.y, &v.z) == 3 && is_finite(v);
}

bool parse(const std::vector<std::string>& args, BakeArgs& a) {
  auto& s = a.settings;
  s.atlas.resolution = 512;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& k = args[i];
    auto value = [&]() -> const char* {
      if (i + 1 >= args.size()) {
        std::fprintf(stderr, "luxel bake: %s needs a value\n", k.c_str());
        return nullptr;
      }
      return args[++i].c_str();
    };
    auto number = [&](double& out) -> bool {
      const char* v = value();
      if (!v) return false;
      char* end = nullptr;
      out = std::strtod(v, &end);
      if (*v == '\0' || *end != '\0' || !std::isfinite(out)) {
        std::fprintf(stderr, "luxel bake: %s expects a number, got '%s'\n", k.c_str(), v);
        return false;
      }
      return true;
    };
    double x = 0;
    if (k == "--help" || k == "-h") { std::fputs(kUsage, stdout); std::exit(0); }
    if (k == "--local") a.local = true;
    else if (k == "--quiet") a.quiet = true;
    else if (k == "--no-compaction") s.compaction = false;
    else if (k == "--sort-directions") s.sort_directions = true;
    else if (k == "--random-sequence") s.random_sequence = true;
    else if (k == "--out") { const char* v = value(); if (!v) return false; a.out = v; }
    else if (k == "--device") { const char* v = value(); if (!v) return false; a.device = v; }
    else if (k == "--samples") { if (!number(x)) return false; s.samples_per_texel = x < 0 ? 0xFFFFFFFFu : static_cast<uint32_t>(x); if (x < 0) { std::fprintf(stderr, "luxel bake: --samples must be >= 0\n"); return false; } }
    else if (k == "--time") { if (!number(x)) return false; s.time_budget_s = x; }
    else if (k == "--target-error") { if (!number(x)) return false; s.target_error = x; }
    else if (k == "--bounces") { if (!number(x)) return false; s.max_bounces = static_cast<int>(x); }
    else if (k == "--resolution") { if (!number(x)) return false; s.atlas.resolution = static_cast<int>(x); s.atlas.texel_density = 0; }
    else if (k == "--texel-density") { if (!number(x)) return false; s.atlas.texel_density = static_cast<float>(x); s.atlas.resolution = 0; }
    else if (k == "--seed") { if (!number(x)) return false; s.seed = static_cast<uint32_t>(x); }
    else if (k == "--paths-per-iteration") { if (!number(x)) return false; s.paths_per_iteration = static_cast<uint32_t>(x); }
    else if (k == "--rr-depth") { if (!number(x)) return false; s.rr_depth = static_cast<int>(x); }
    else if (k == "--clamp") { if (!number(x)) return false; s.clamp_luminance = static_cast<float>(x); }
    else if (k == "--dilate") { if (!number(x)) return false; s.dilation_texels = static_cast<int>(x); }
    else if (k == "--progress-interval") { if (!number(x)) return false; s.progress_interval_s = x; }
    else if (k == "--filter") {
      const char* v = value();
      if (!v) return false;
      if (std::string(v) == "box") s.filter = pipeline::Filter::kBox;
      else if (std::string(v) == "gaussian") s.filter = pipeline::Filter::kGaussian;
      else { std::fprintf(stderr, "luxel bake: --filter must be box or gaussian, got '%s'\n", v); return false; }
    } else if (k == "--sky") {
      const char* v = value();
      if (!v) return false;
      if (!parse_vec3(v, s.lights.sky.color)) { std::fprintf(stderr, "luxel bake: --sky expects R,G,B, got '%s'\n", v); return false; }
      s.lights.sky.kind = pipeline::SkySettings::Kind::kConstant;
    } else if (k == "--sky-image") {
      const char* v = value();
      if (!v) return false;
      s.lights.sky.kind = pipeline::SkySettings::Kind::kEquirect;
      s.lights.sky.equirect_path = v;
    } else if (k == "--sky-intensity") { if (!number(x)) return false; s.lights.sky.intensity = static_cast<float>(x); }
    else if (k == "--sky-rotation") { if (!number(x)) return false; s.lights.sky.rotation_degrees = static_cast<float>(x); }
    else if (k == "--sun") {
      const char* v = value();
      if (!v) return false;
      if (!parse_vec3(v, s.lights.sun.direction)) { std::fprintf(stderr, "luxel bake: --sun expects X,Y,Z, got '%s'\n", v); return false; }
      s.lights.sun.enabled = true;
    } else if (k == "--sun-illuminance") { if (!number(x)) return false; s.lights.sun.illuminance = static_cast<float>(x); }
    else if (k == "--sun-radius") { if (!number(x)) return false; s.lights.sun.angular_radius_degrees = static_cast<float>(x); }
    else if (k == "--directional-radius") { if (!number(x)) return false; s.lights.directional_angular_radius_degrees = static_cast<float>(x); }
    else if (!k.empty() && k[0] == '-') { std::fprintf(stderr, "luxel bake: unknown option '%s'\n%s", k.c_str(), kUsage); return false; }
    else if (a.scene.empty()) a.scene = k;
    else { std::fprintf(stderr, "luxel bake: unexpected argument '%s'\n", k.c_str()); return false; }
  }
  if (a.scene.empty() || a.out.empty()) {
    std::fprintf(stderr, "luxel bake: a SCENE and --out DIR are required\n%s", kUsage);
    return false;
  }
  return true;
}

std::string format_duration(double s) {
  if (s < 0) return "--";
  if (s < 60) return strprintf("%.0fs", s);
  if (s < 3600) return strprintf("%dm%02ds", int(s) / 60, int(s) % 60);
  return strprintf("%dh%02dm", int(s) / 3600, (int(s) / 60) % 60);
}

void draw_progress(const pipeline::BakeProgress& p, bool tty) {
  const int width = 30;
  const int filled = static_cast<int>(p.fraction * width + 0.5);
  std::string bar(static_cast<size_t>(filled), '#');
  bar.resize(width, '.');
  std::fprintf(stdout, "%s[%s] %5.1f%%  spp %.1f (min %u)  error %.4f  %s elapsed  ETA %s%s",
               tty ? "\r" : "", bar.c_str(), 100.0 * p.fraction, p.mean_spp, p.min_spp, p.error,
               format_duration(p.elapsed_s).c_str(), format_duration(p.eta_s).c_str(),
               tty ? "   " : "\n");
  std::fflush(stdout);
}

}  // namespace

int run_bake(const std::vector<std::string>& args) {
  BakeArgs a;
  if (!parse(args, a)) return 2;
  if (!a.local) {
    std::fprintf(stderr,
                 "luxel bake: only in-process baking exists in this version; pass --local\n");
    return 2;
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
  std::printf("scene      %s\ndevice     %s\n", a.scene.c_str(), ctx.value()->info().describe().c_str());
  const bool tty = isatty(fileno(stdout));
  auto result = pipeline::bake(scene.value(), a.settings, *ctx.value(),
                               [&](const pipeline::BakeProgress& p) {
                                 if (!a.quiet) draw_progress(p, tty);
                                 return true;
                               });
  if (tty && !a.quiet) std::printf("\n");
  if (!result) {
    std::fprintf(stderr, "luxel bake: %s\n", result.status().to_string().c_str());
    return 1;
  }
  const auto& r = result.value();
  auto paths = pipeline::write_bake_outputs(a.out, scene.value(), a.settings, r);
  if (!paths) {
    std::fprintf(stderr, "luxel bake: %s\n", paths.status().to_string().c_str());
    return 1;
  }
  std::printf("lightmap   %dx%d (%s atlas), %zu covered texels, sample-info buffer %.1f MiB\n",
              r.width, r.height, atlas::atlas_mode_name(r.atlas.mode), r.covered_texels,
              r.sample_info_bytes / 1048576.0);
  std::printf("features   %s\n", r.features.c_str());
  std::printf("baked      %.2f s (+%.2f s setup), %llu paths (%.2f Mpaths/s), spp mean %.1f min %u, "
              "error %.4f, stopped by %s\n",
              r.seconds, r.setup_s, static_cast<unsigned long long>(r.paths),
              r.seconds > 0 ? r.paths / r.seconds / 1e6 : 0.0, r.mean_spp, r.min_spp, r.error,
              pipeline::termination_name(r.termination));
  if (r.nonfinite_dropped > 0)
    std::printf("warning    %llu non-finite samples dropped\n",
                static_cast<unsigned long long>(r.nonfinite_dropped));
  std::printf("memory     %.1f MiB on the device\n", r.peak_device_bytes / 1048576.0);
  std::printf("\nkernel timings (OpenCL profiling events)\n%s", r.kernel_table.c_str());
  std::printf("\nwrote      %s\n           %s\n           %s\n", paths.value().irradiance_exr.c_str(),
              paths.value().preview_png.c_str(), paths.value().manifest_json.c_str());
  return 0;
}

}  // namespace luxel::cli
