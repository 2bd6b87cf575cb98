// bench_denoise: accuracy and cost of the lightmap denoisers, a-trous
// (post/denoise.h) and Open Image Denoise's RTLightmap (post/oidn.h), the
// figures of docs/accuracy.md "Denoiser" and "Open Image Denoise".
//
//   bench_denoise [--resolution N] [--bounces B] [--ref-spp N] [--spp 4,16,64]
//                 [--sky] [--ref-cache FILE.exr]
//                 [--sigma-l X] [--sigma-n X] [--iterations N] SCENE
//   bench_denoise --timing 512,2048
//
// Accuracy: a converged reference (seed 99, --ref-spp samples, denoise off;
// cached in --ref-cache) and bakes at each --spp (seed 1). For each: RMSE
// over covered texels and RGB, and relMSE = mean (x - ref)^2 / (ref^2 +
// 1e-2), of the raw and the denoised lightmap, on all covered texels and on
// "edge" texels: within 2 texels (Chebyshev) of a chart border or an
// uncovered texel, of a neighbour in the same chart whose normal differs by
// more than 25 degrees, or of a shadow boundary (4-neighbours whose
// reference luminance differs by more than a factor 2).
//
// --sigma-l / --sigma-n / --iterations: the filter run again with these
// parameters (DenoiseParams) instead of the bake's defaults.
//
// One row per spp and filter: raw, a-trous (the bake's), and, when its
// library loads, OIDN run on the same raw bake and variances as a bake with
// `denoise = oidn` runs it (per chart, blended) and without the blend; the
// OIDN rows give the filter's seconds per megatexel of filtered crops.
//
// --timing: an open plane covering an N x N lightmap (2 samples per texel,
// constant sky); CPU (user + sys, all threads) and wall seconds of building
// the host guides, and of one filter run (upload, 5 launches, read back; the
// best of 3 after a warm-up run), per N; and OIDN's wall seconds for the same
// image (one chart: one filter call; best of 3), with seconds per megatexel.
#include "post/denoise.h"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "atlas/sample_info.h"
#include "bake/bake.h"
#include "common/clock.h"
#include "device/context.h"
#include "output/exr.h"
#include "post/denoise_guides.h"
#include "post/oidn.h"
#include "scene/gltf_import.h"

using namespace luxel;

namespace {

[[noreturn]] void die(const std::string& what) {
  std::fprintf(stderr, "bench_denoise: %s\n", what.c_str());
  std::exit(1);
}

std::vector<int> parse_list(const char* s) {
  std::vector<int> out;
  for (const char* p = s; *p;) {
    out.push_back(std::atoi(p));
    while (*p && *p != ',') ++p;
    if (*p) ++p;
  }
  return out;
}

pipeline::BakeResult run_bake(const scene::Scene& s, const pipeline::BakeSettings& st,
                              device::Context& ctx) {
  auto r = pipeline::bake(s, st, ctx);
  if (!r) die(r.status().to_string());
  return std::move(r.value());
}

double luminance(const float* c) {
  return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
}

// Texels counted as "edge" (see the header comment).
std::vector<char> edge_texels(const pipeline::DenoiseGuides& g, const std::vector<float>& ref) {
  const int w = g.width, h = g.height;
  std::vector<char> seed(size_t(w) * h, 0), edge(size_t(w) * h, 0);
  auto covered = [&](int x, int y) { return g.position[size_t(y) * w + x].w > 0; };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t t = size_t(y) * w + x;
      if (!covered(x, y)) continue;
      const int dx[4] = {1, -1, 0, 0}, dy[4] = {0, 0, 1, -1};
      for (int k = 0; k < 4; ++k) {
        const int qx = x + dx[k], qy = y + dy[k];
        if (qx < 0 || qy < 0 || qx >= w || qy >= h || !covered(qx, qy)) {
          seed[t] = 1;
          continue;
        }
        const size_t q = size_t(qy) * w + qx;
        if (g.chart[q] != g.chart[t]) seed[t] = 1;
        const auto& a = g.normal[t];
        const auto& b = g.normal[q];
        if (a.x * b.x + a.y * b.y + a.z * b.z < std::cos(25.0 * M_PI / 180)) seed[t] = 1;
        const double la = luminance(&ref[t * 4]), lb = luminance(&ref[q * 4]);
        if (std::max(la, lb) > 1e-3 && std::max(la, lb) > 2 * std::min(la, lb)) seed[t] = 1;
      }
    }
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (!seed[size_t(y) * w + x]) continue;
      for (int qy = std::max(0, y - 2); qy <= std::min(h - 1, y + 2); ++qy)
        for (int qx = std::max(0, x - 2); qx <= std::min(w - 1, x + 2); ++qx)
          if (covered(qx, qy)) edge[size_t(qy) * w + qx] = 1;
    }
  return edge;
}

struct Err {
  double rmse = 0, rel_mse = 0;
  size_t texels = 0;
};

Err error(const std::vector<float>& x, const std::vector<float>& ref, const std::vector<float>& raw,
          const std::vector<char>* mask) {
  Err e;
  double sq = 0, rel = 0;
  for (size_t t = 0; t < ref.size() / 4; ++t) {
    if (raw[t * 4 + 3] <= 0 || (mask && !(*mask)[t])) continue;
    for (int c = 0; c < 3; ++c) {
      const double d = double(x[t * 4 + c]) - ref[t * 4 + c];
      sq += d * d;
      rel += d * d / (double(ref[t * 4 + c]) * ref[t * 4 + c] + 1e-2);
    }
    ++e.texels;
  }
  e.rmse = std::sqrt(sq / (3.0 * std::max<size_t>(e.texels, 1)));
  e.rel_mse = rel / (3.0 * std::max<size_t>(e.texels, 1));
  return e;
}

// User + system seconds of the whole process (PoCL's worker threads included).
double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

void timing(const std::vector<int>& sizes, device::Context& ctx) {
  std::printf(
      "| lightmap | covered texels | guides CPU s | guides wall s | filter CPU s (5 launches + "
      "transfers) | filter wall s | OIDN wall s | OIDN s per Mtexel |\n"
      "|---|---|---|---|---|---|---|---|\n");
  auto oidn = pipeline::load_oidn();
  for (int n : sizes) {
    scene::Scene s;
    s.source_name = "plane";
    scene::Material m;
    m.base_color_factor = {0.5f, 0.5f, 0.5f, 1};
    s.materials.push_back(m);
    scene::Mesh mesh;
    mesh.positions = {{-1, 0, -1}, {-1, 0, 1}, {1, 0, 1}, {1, 0, -1}};
    mesh.normals.assign(4, Vec3{0, 1, 0});
    mesh.uv0 = mesh.uv1 = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    mesh.indices = {0, 1, 2, 0, 2, 3};
    mesh.triangle_material = {0, 0};
    s.meshes.push_back(mesh);
    scene::Instance inst;
    inst.name = "plane";
    inst.mesh = 0;
    s.instances.push_back(inst);
    pipeline::BakeSettings st;
    st.atlas.resolution = n;
    st.samples_per_texel = 2;
    st.max_bounces = 0;
    st.lights.sky.kind = pipeline::SkySettings::Kind::kConstant;
    st.denoise = pipeline::Denoise::kOff;
    const pipeline::BakeResult r = run_bake(s, st, ctx);
    auto info = atlas::build_sample_info(s, r.atlas);
    if (!info) die(info.status().to_string());
    const double c0 = cpu_seconds();
    const auto t0 = std::chrono::steady_clock::now();
    const auto guides = pipeline::build_denoise_guides(s, r.atlas, info.value());
    const double guide_wall = seconds_since(t0), guide_cpu = cpu_seconds() - c0;
    auto d = pipeline::Denoiser::create(ctx, guides);
    if (!d) die(d.status().to_string());
    const auto variance = pipeline::texel_variance(r.irradiance, r.rel_error);
    if (!d.value()->run(r.irradiance, variance, {})) die("denoise failed");  // JIT warm-up
    double best_wall = 1e30, best_cpu = 1e30;
    for (int k = 0; k < 3; ++k) {
      const double c = cpu_seconds();
      const auto t = std::chrono::steady_clock::now();
      if (!d.value()->run(r.irradiance, variance, {})) die("denoise failed");
      best_wall = std::min(best_wall, seconds_since(t));
      best_cpu = std::min(best_cpu, cpu_seconds() - c);
    }
    double oidn_wall = 0, oidn_per_mtexel = 0;
    if (oidn) {
      pipeline::OidnDenoiser od(*oidn.value(), guides, r.atlas.pages);
      oidn_wall = 1e30;
      for (int k = 0; k < 3; ++k) {
        const auto t = std::chrono::steady_clock::now();
        if (!od.run(r.irradiance, variance, {})) die("oidn failed");
        if (seconds_since(t) < oidn_wall)
          oidn_wall = seconds_since(t), oidn_per_mtexel = od.stats().seconds_per_megatexel();
      }
    }
    std::printf("| %d² | %zu | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f |\n", n, r.covered_texels,
                guide_cpu, guide_wall, best_cpu, best_wall, oidn_wall, oidn_per_mtexel);
  }
}

}  // namespace

int main(int argc, char** argv) {
  int resolution = 128, bounces = 4, ref_spp = 4096;
  std::vector<int> spps = {4, 16, 64}, timing_sizes;
  bool sky = false;
  pipeline::DenoiseParams params;  // --sigma-l, --iterations: run the filter with these
  bool custom = false;
  std::string scene_path, ref_cache;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&] {
      if (i + 1 >= argc) die("missing value after " + a);
      return argv[++i];
    };
    if (a == "--resolution")
      resolution = std::atoi(next());
    else if (a == "--bounces")
      bounces = std::atoi(next());
    else if (a == "--ref-spp")
      ref_spp = std::atoi(next());
    else if (a == "--spp")
      spps = parse_list(next());
    else if (a == "--sky")
      sky = true;
    else if (a == "--ref-cache")
      ref_cache = next();
    else if (a == "--timing")
      timing_sizes = parse_list(next());
    else if (a == "--sigma-l")
      params.sigma_luminance = float(std::atof(next())), custom = true;
    else if (a == "--sigma-n")
      params.sigma_normal = float(std::atof(next())), custom = true;
    else if (a == "--iterations")
      params.iterations = std::atoi(next()), custom = true;
    else
      scene_path = a;
  }
  auto ctx = device::Context::create();
  if (!ctx) die(ctx.status().to_string());
  if (!timing_sizes.empty()) {
    timing(timing_sizes, *ctx.value());
    return 0;
  }
  if (scene_path.empty()) die("no scene");
  auto scene = scene::import_gltf_file(scene_path);
  if (!scene) die(scene.status().to_string());
  pipeline::BakeSettings st;
  st.atlas.resolution = resolution;
  st.max_bounces = bounces;
  st.denoise = pipeline::Denoise::kAtrous;  // off by default: the bake gives a-trous's map
  if (sky) {
    st.lights.sky.kind = pipeline::SkySettings::Kind::kConstant;
    st.lights.sky.color = {0.4f, 0.5f, 0.7f};
    st.lights.sun.enabled = true;
    st.lights.sun.direction = {0.3f, -1.0f, 0.2f};
    st.lights.sun.illuminance = 5.0f;
  }

  std::vector<float> ref;
  if (!ref_cache.empty() && std::filesystem::exists(ref_cache)) {
    auto img = output::read_exr(ref_cache);
    if (!img) die(img.status().to_string());
    ref = img.value().pixels;
  } else {
    pipeline::BakeSettings rs = st;
    rs.samples_per_texel = uint32_t(ref_spp);
    rs.seed = 99;
    rs.denoise = pipeline::Denoise::kOff;
    const pipeline::BakeResult r = run_bake(scene.value(), rs, *ctx.value());
    ref = r.irradiance;
    std::fprintf(stderr, "reference: %d spp, %.1f s\n", ref_spp, r.seconds);
    if (!ref_cache.empty()) {
      output::Image img{r.width, r.height, 4, ref};
      if (auto s = output::write_exr(ref_cache, img, {"R", "G", "B", "A"}, {}); !s.is_ok())
        die(s.to_string());
    }
  }

  auto oidn = pipeline::load_oidn();
  if (!oidn) std::fprintf(stderr, "no OIDN rows: %s\n", oidn.status().message().c_str());
  std::printf(
      "| spp | filter | all: RMSE | relMSE | edges: RMSE | relMSE | filter s per Mtexel |\n"
      "|---|---|---|---|---|---|---|\n");
  for (int spp : spps) {
    st.samples_per_texel = uint32_t(spp);
    st.seed = 1;
    const pipeline::BakeResult r = run_bake(scene.value(), st, *ctx.value());
    if (r.irradiance.size() != ref.size()) die("reference size differs (stale --ref-cache?)");
    auto info = atlas::build_sample_info(scene.value(), r.atlas);
    if (!info) die(info.status().to_string());
    const auto guides = pipeline::build_denoise_guides(scene.value(), r.atlas, info.value());
    const auto edges = edge_texels(guides, ref);
    std::vector<float> denoised = r.irradiance_denoised;
    if (custom) {
      auto d = pipeline::Denoiser::create(*ctx.value(), guides);
      if (!d) die(d.status().to_string());
      // The variances the bake's own denoiser used (two-point estimates).
      auto o = d.value()->run(r.irradiance, r.denoise_variance, params);
      if (!o) die(o.status().to_string());
      denoised = std::move(o.value());
    }
    auto row = [&](const char* name, const std::vector<float>& x, double per_mtexel) {
      const Err a = error(x, ref, r.irradiance, nullptr);
      const Err e = error(x, ref, r.irradiance, &edges);
      std::printf("| %d | %s | %.4g | %.4g | %.4g | %.4g | %s |\n", spp, name, a.rmse, a.rel_mse,
                  e.rmse, e.rel_mse, per_mtexel > 0 ? strprintf("%.3f", per_mtexel).c_str() : "-");
    };
    row("raw", r.irradiance, 0);
    row("a-trous", denoised, 0);
    if (oidn) {
      pipeline::OidnDenoiser od(*oidn.value(), guides, r.atlas.pages);
      const std::pair<pipeline::OidnBlend, const char*> blends[] = {
          {pipeline::OidnBlend::kShrink, "oidn (shrink, the bake's)"},
          {pipeline::OidnBlend::kClamp, "oidn, clamp 1 SE"},
          {pipeline::OidnBlend::kNone, "oidn, no blend"}};
      for (const auto& [blend, label] : blends) {
        pipeline::OidnParams p;
        p.blend = blend;
        auto o = od.run(r.irradiance, r.denoise_variance, p);
        if (!o) die(o.status().to_string());
        row(label, o.value(), od.stats().seconds_per_megatexel());
      }
    }
    std::fflush(stdout);
  }
  return 0;
}
