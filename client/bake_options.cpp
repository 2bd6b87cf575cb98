#include "bake_options.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace luxel::cli {
namespace {

const char* kUsage =
    "usage: luxel bake SCENE --out DIR [options]            (on a luxeld daemon)\n"
    "       luxel bake SCENE --local --out DIR [options]    (in this process)\n"
    "settings:\n"
    "  --samples N           samples per texel to reach (default 256; 0 = no sample limit)\n"
    "  --time SECONDS        time budget for path tracing\n"
    "  --target-error E      stop at this mean relative standard error (e.g. 0.02)\n"
    "  --bounces B           indirect bounces (default 4; 0 = direct light only)\n"
    "  --resolution N        lightmap side in texels (default 512)\n"
    "  --texel-density D     texels per world unit (instead of --resolution)\n"
    "  --seed S              random seed (same seed, same result)\n"
    "  --filter box|gaussian accumulation filter (default box)\n"
    "  --encoding LIST       irradiance plus directional encodings, comma-separated:\n"
    "                        sh1, sh2, sg6|sg9|sg12[-hemi], ambient-dice9|12 (default irradiance)\n"
    "  --sg-sharpness L      spherical Gaussian lambda (default 3.4)\n"
    "  --solver S            auto|projection|progressive|progressive-nn (default auto:\n"
    "                        projection for SH, progressive-nn for SG and Ambient Dice)\n"
    "  --acceleration A      progressive least-squares alpha, Eq. 7.14 (default 3)\n"
    "  --target-metric M     what --target-error bounds: estimate (default), rmse, relmse\n"
    "                        (rmse/relmse need a reference: --reference or --reference-bake)\n"
    "  --sky R,G,B           constant sky radiance  [--sky-intensity X]\n"
    "  --sun X,Y,Z           sun travelling along X,Y,Z  [--sun-illuminance E] [--sun-radius DEG]\n"
    "  --paths-per-iteration N   batch size (default 262144)\n"
    "  --dilate N            dilate uncovered texels by N (default 2)\n"
    "  --quiet               no progress bar\n"
    "remote (default; SCENE may also be the id of a scene the daemon stores):\n"
    "  --priority P          higher runs first (default 0)\n"
    "  --snapshot-interval S seconds between progressive snapshots\n"
    "  --snapshot-format png|exr|none   --snapshot-size N (PNG longest side)\n"
    "  --snapshots DIR       write each snapshot to DIR/snapshot_NNNN.png while watching\n"
    "  --idempotency-key K   a retry with the same key returns the same bake\n"
    "  --reference-bake ID   benchmark mode: that finished bake's lightmap is the reference\n"
    "  --name NAME           scene display name when it is uploaded\n"
    "  --detach              print the bake id after submitting and return\n"
    "  (and the connection options of `luxel upload --help`)\n"
    "exit codes: 0 done, 1 error (daemon, network, files), 2 usage, 3 bake failed/cancelled\n"
    "--local only:\n"
    "  --sky-image FILE      equirectangular HDR/EXR sky  [--sky-rotation DEG]\n"
    "  --reference FILE.exr  benchmark mode: RMSE and relMSE against this lightmap (RGBA,\n"
    "                        same size, e.g. a converged bake's irradiance.exr) in every report\n"
    "  --directional-radius DEG  angular radius of the scene's directional lights\n"
    "  --rr-depth D          Russian roulette from this depth (default 3)\n"
    "  --clamp L             clamp path luminance (biased; default off)\n"
    "  --no-compaction, --sort-directions, --random-sequence   ablation switches\n"
    "  --progress-interval S seconds between progress updates (default 1)\n"
    "  --device SPEC         OpenCL device (see `luxel devices`)\n";

bool parse_vec3(const std::string& s, Vec3& v) {
  return std::sscanf(s.c_str(), "%f,%f,%f", &v.x, &v.y, &v.z) == 3 && is_finite(v);
}

bool is_local_only(const std::string& k) {
  for (const char* o : {"--sky-image", "--sky-rotation", "--directional-radius", "--rr-depth", "--reference",
                        "--clamp", "--no-compaction", "--sort-directions", "--random-sequence",
                        "--progress-interval", "--device"})
    if (k == o) return true;
  return false;
}

bool is_remote_only(const std::string& k) {
  for (const char* o : {"--priority", "--snapshot-interval", "--snapshot-format", "--snapshot-size",
                        "--snapshots", "--idempotency-key", "--name", "--detach", "--server", "--reference-bake",
                        "--token", "--tls-ca", "--tls", "--timeout", "--json"})
    if (k == o) return true;
  return false;
}

}  // namespace

ParseOutcome parse_bake_args(const std::vector<std::string>& args, BakeArgs& a) {
  auto& s = a.settings;
  s.atlas.resolution = 512;
  a.connection = remote::default_connection_options();
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& k = args[i];
    if (is_local_only(k)) a.local_only.push_back(k);
    if (is_remote_only(k)) a.remote_only.push_back(k);
    const auto m = remote::take_connection_option("bake", args, i, a.connection);
    if (m == remote::OptionMatch::kError) return ParseOutcome::kUsageError;
    if (m == remote::OptionMatch::kTaken) continue;
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
    auto text = [&](std::string& out) -> bool {
      const char* v = value();
      if (v) out = v;
      return v != nullptr;
    };
    double x = 0;
    bool ok = true;
    if (k == "--help" || k == "-h") {
      std::printf("%s%s", kUsage, remote::kConnectionUsage);
      return ParseOutcome::kHelpShown;
    }
    if (k == "--local") a.local = true;
    else if (k == "--quiet") a.quiet = true;
    else if (k == "--detach") a.detach = true;
    else if (k == "--no-compaction") s.compaction = false;
    else if (k == "--sort-directions") s.sort_directions = true;
    else if (k == "--random-sequence") s.random_sequence = true;
    else if (k == "--out") ok = text(a.out);
    else if (k == "--device") ok = text(a.device);
    else if (k == "--name") ok = text(a.name);
    else if (k == "--snapshots") ok = text(a.snapshots_dir);
    else if (k == "--idempotency-key") ok = text(a.idempotency_key);
    else if (k == "--reference") ok = text(a.reference_file);
    else if (k == "--reference-bake") ok = text(a.reference_bake);
    else if (k == "--target-metric") {
      std::string v;
      ok = text(v);
      if (ok) {
        auto metric = pipeline::parse_error_metric(v);
        if (!metric) { std::fprintf(stderr, "luxel bake: --target-metric: %s\n", metric.status().message().c_str()); ok = false; }
        else s.target_metric = metric.value();
      }
    }
    else if (k == "--snapshot-format") {
      ok = text(a.snapshot_format);
      if (ok && a.snapshot_format != "png" && a.snapshot_format != "exr" && a.snapshot_format != "none") {
        std::fprintf(stderr, "luxel bake: --snapshot-format must be png, exr or none, got '%s'\n",
                     a.snapshot_format.c_str());
        ok = false;
      }
    }
    else if (k == "--priority") { ok = number(x); a.priority = static_cast<int>(x); }
    else if (k == "--snapshot-interval") { ok = number(x); a.snapshot_interval_s = x; }
    else if (k == "--snapshot-size") {
      ok = number(x);
      if (ok && x < 0) { std::fprintf(stderr, "luxel bake: --snapshot-size must be >= 0\n"); ok = false; }
      a.snapshot_max_side = static_cast<uint32_t>(std::max(x, 0.0));
    }
    else if (k == "--samples") {
      ok = number(x);
      if (ok && x < 0) { std::fprintf(stderr, "luxel bake: --samples must be >= 0\n"); ok = false; }
      s.samples_per_texel = static_cast<uint32_t>(std::max(x, 0.0));
    }
    else if (k == "--time") { ok = number(x); s.time_budget_s = x; }
    else if (k == "--target-error") { ok = number(x); s.target_error = x; }
    else if (k == "--bounces") { ok = number(x); s.max_bounces = static_cast<int>(x); }
    else if (k == "--resolution") { ok = number(x); s.atlas.resolution = static_cast<int>(x); s.atlas.texel_density = 0; }
    else if (k == "--texel-density") { ok = number(x); s.atlas.texel_density = static_cast<float>(x); s.atlas.resolution = 0; }
    else if (k == "--seed") { ok = number(x); s.seed = static_cast<uint32_t>(x); }
    else if (k == "--paths-per-iteration") { ok = number(x); s.paths_per_iteration = static_cast<uint32_t>(x); }
    else if (k == "--rr-depth") { ok = number(x); s.rr_depth = static_cast<int>(x); }
    else if (k == "--clamp") { ok = number(x); s.clamp_luminance = static_cast<float>(x); }
    else if (k == "--dilate") { ok = number(x); s.dilation_texels = static_cast<int>(x); }
    else if (k == "--progress-interval") { ok = number(x); s.progress_interval_s = x; }
    else if (k == "--encoding") {
      std::string v;
      ok = text(v);
      if (ok) {
        auto names = pipeline::parse_encoding_list(v);
        if (!names) { std::fprintf(stderr, "luxel bake: --encoding: %s\n", names.status().message().c_str()); ok = false; }
        else s.encodings.names = names.value();
      }
    } else if (k == "--solver") {
      std::string v;
      ok = text(v);
      if (ok) {
        auto solver = pipeline::parse_solver(v);
        if (!solver) { std::fprintf(stderr, "luxel bake: --solver: %s\n", solver.status().message().c_str()); ok = false; }
        else s.encodings.solver = solver.value();
      }
    }
    else if (k == "--sg-sharpness") { ok = number(x); s.encodings.sg_sharpness = static_cast<float>(x); }
    else if (k == "--acceleration") { ok = number(x); s.encodings.acceleration = static_cast<float>(x); }
    else if (k == "--filter") {
      std::string v;
      ok = text(v);
      if (v == "box") s.filter = pipeline::Filter::kBox;
      else if (v == "gaussian") s.filter = pipeline::Filter::kGaussian;
      else if (ok) { std::fprintf(stderr, "luxel bake: --filter must be box or gaussian, got '%s'\n", v.c_str()); ok = false; }
    } else if (k == "--sky") {
      std::string v;
      ok = text(v);
      if (ok && !parse_vec3(v, s.lights.sky.color)) { std::fprintf(stderr, "luxel bake: --sky expects R,G,B, got '%s'\n", v.c_str()); ok = false; }
      s.lights.sky.kind = pipeline::SkySettings::Kind::kConstant;
    } else if (k == "--sky-image") {
      ok = text(s.lights.sky.equirect_path);
      s.lights.sky.kind = pipeline::SkySettings::Kind::kEquirect;
    } else if (k == "--sky-intensity") { ok = number(x); s.lights.sky.intensity = static_cast<float>(x); }
    else if (k == "--sky-rotation") { ok = number(x); s.lights.sky.rotation_degrees = static_cast<float>(x); }
    else if (k == "--sun") {
      std::string v;
      ok = text(v);
      if (ok && !parse_vec3(v, s.lights.sun.direction)) { std::fprintf(stderr, "luxel bake: --sun expects X,Y,Z, got '%s'\n", v.c_str()); ok = false; }
      s.lights.sun.enabled = true;
    } else if (k == "--sun-illuminance") { ok = number(x); s.lights.sun.illuminance = static_cast<float>(x); }
    else if (k == "--sun-radius") { ok = number(x); s.lights.sun.angular_radius_degrees = static_cast<float>(x); }
    else if (k == "--directional-radius") { ok = number(x); s.lights.directional_angular_radius_degrees = static_cast<float>(x); }
    else if (!k.empty() && k[0] == '-') { std::fprintf(stderr, "luxel bake: unknown option '%s' (luxel bake --help)\n", k.c_str()); ok = false; }
    else if (a.scene.empty()) a.scene = k;
    else { std::fprintf(stderr, "luxel bake: unexpected argument '%s'\n", k.c_str()); ok = false; }
    if (!ok) return ParseOutcome::kUsageError;
  }
  if (a.scene.empty() || (a.out.empty() && !a.detach)) {
    std::fprintf(stderr, "luxel bake: a SCENE and --out DIR are required (luxel bake --help)\n");
    return ParseOutcome::kUsageError;
  }
  return ParseOutcome::kOk;
}

}  // namespace luxel::cli
