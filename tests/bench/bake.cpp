// bench_bake: throughput of the bake engine.
//
//   bench_bake [--spp N] [--resolution N] [--quick] [--kernels N] [--default-only]
//              [SCENE...]
//   bench_bake --memory ENCODINGS [--budget MIB] [--spp N] [--resolution N] [SCENE...]
//
// --memory: one bake per scene with the directional encodings given
// (comma-separated, e.g. sg12) under the device-memory budget (default: the
// engine's), 1 bounce; prints time, peak device memory, tiles and the
// host's peak resident memory. No files are written.
//
// --kernels N: each row names its N largest kernels (default 4).
// --default-only: only the default configuration's row.
//
// For each scene, in one run on one device:
//  1. paths/s and the per-kernel breakdown at 1 and 4 bounces through each
//     ray-query backend (Embree, OpenCL), peak device memory;
//  2. paths/s against the batch size (paths per iteration);
//  3. ablations at 4 bounces: stream compaction off, ray-direction sorting on
//     (time for the same number of paths, as a ratio to the default).
// Scenes get a constant sky and a sun so outdoor scenes have light.
#include "bake/bake.h"

#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "device/context.h"
#include "scene/gltf_import.h"

using namespace luxel;

namespace {

// How many of the largest kernels a row names (--kernels N).
size_t g_top_kernels = 4;

struct Run {
  double seconds = 0, mpaths_per_s = 0, kernel_ms = 0;
  size_t device_mib = 0;
  std::string top_kernels;
};

// Each configuration is baked twice and the second bake is measured: the
// first builds and caches its program variant and lets PoCL JIT-compile the
// work-group functions for the launch sizes used (which depend on the batch
// size), so the measured bake pays for no compilation.
Run bake_once(const scene::Scene& s, pipeline::BakeSettings st, device::Context& ctx) {
  if (!pipeline::bake(s, st, ctx)) std::exit(1);
  auto r = pipeline::bake(s, st, ctx);
  if (!r) {
    std::fprintf(stderr, "bench_bake: %s\n", r.status().to_string().c_str());
    std::exit(1);
  }
  Run run;
  run.seconds = r.value().seconds;
  run.mpaths_per_s = r.value().paths / r.value().seconds / 1e6;
  run.device_mib = r.value().peak_device_bytes >> 20;
  auto kernels = r.value().kernel_ms;
  std::sort(kernels.begin(), kernels.end(), [](auto& a, auto& b) { return a.second > b.second; });
  for (const auto& k : kernels) run.kernel_ms += k.second;
  for (size_t i = 0; i < kernels.size() && i < g_top_kernels; ++i)
    run.top_kernels += strprintf("%s%s %.0f%%", i ? ", " : "", kernels[i].first.c_str(),
                                 100.0 * kernels[i].second / run.kernel_ms);
  return run;
}

}  // namespace

int main(int argc, char** argv) {
  uint32_t spp = 16;
  int resolution = 256;
  bool quick = false, default_only = false;
  std::string memory_encodings;
  double budget_mib = 0;
  std::vector<std::string> scenes;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--spp" && i + 1 < argc)
      spp = static_cast<uint32_t>(std::atoi(argv[++i]));
    else if (a == "--resolution" && i + 1 < argc)
      resolution = std::atoi(argv[++i]);
    else if (a == "--kernels" && i + 1 < argc)
      g_top_kernels = static_cast<size_t>(std::atoi(argv[++i]));
    else if (a == "--default-only")
      default_only = true;
    else if (a == "--quick")
      quick = true;
    else if (a == "--memory" && i + 1 < argc)
      memory_encodings = argv[++i];
    else if (a == "--budget" && i + 1 < argc)
      budget_mib = std::atof(argv[++i]);
    else
      scenes.push_back(a);
  }
  if (scenes.empty())
    scenes = {LUXEL_SCENES_DIR "/cornell_box.gltf", LUXEL_SCENES_DIR "/foliage_instanced.glb",
              LUXEL_SCENES_DIR "/procedural_city.glb"};
  auto ctx = device::Context::create();
  if (!ctx) {
    std::fprintf(stderr, "bench_bake: %s\n", ctx.status().to_string().c_str());
    return 1;
  }
  std::printf("device: %s\nlightmap %d^2, %u samples per texel per measurement\n\n",
              ctx.value()->info().describe().c_str(), resolution, spp);

  for (const auto& path : scenes) {
    auto s = scene::import_gltf_file(path);
    if (!s) {
      std::fprintf(stderr, "bench_bake: %s\n", s.status().to_string().c_str());
      return 1;
    }
    pipeline::BakeSettings base;
    base.atlas.resolution = resolution;
    base.samples_per_texel = spp;
    base.lights.sky.kind = pipeline::SkySettings::Kind::kConstant;
    base.lights.sky.color = {0.4f, 0.5f, 0.7f};
    base.lights.sun.enabled = true;
    base.lights.sun.direction = {0.3f, -1.0f, 0.2f};
    base.lights.sun.illuminance = 5.0f;
    base.progress_interval_s = 1e9;
    std::printf("scene %s\n", path.c_str());
    if (!memory_encodings.empty()) {
      auto st = base;
      st.max_bounces = 1;
      st.device_memory_budget_mib = budget_mib;
      for (size_t b = 0, e; b <= memory_encodings.size(); b = e + 1) {
        e = std::min(memory_encodings.find(',', b), memory_encodings.size());
        const std::string name = memory_encodings.substr(b, e - b);
        if (!name.empty() && name != "irradiance") st.encodings.names.push_back(name);
      }
      auto r = pipeline::bake(s.value(), st, *ctx.value());
      if (!r) {
        std::fprintf(stderr, "bench_bake: %s\n", r.status().to_string().c_str());
        return 1;
      }
      rusage ru{};
      getrusage(RUSAGE_SELF, &ru);
      std::printf(
          "  %d^2 %s: setup %.1f s, tracing %.1f s, %zu covered texels, peak device %.1f MiB "
          "(budget %.0f MiB, %zu tiles), host peak RSS %.1f MiB\n",
          resolution, memory_encodings.c_str(), r.value().setup_s, r.value().seconds,
          r.value().covered_texels, r.value().peak_device_bytes / 1048576.0,
          r.value().device_memory_budget / 1048576.0, r.value().tiles, ru.ru_maxrss / 1024.0);
      continue;
    }

    std::printf("  %-28s %9s %9s %10s %8s  %s\n", "configuration", "seconds", "Mpaths/s",
                "kernel ms", "dev MiB", "largest kernels");
    auto row = [&](const std::string& name, const Run& r) {
      std::printf("  %-28s %9.2f %9.3f %10.0f %8zu  %s\n", name.c_str(), r.seconds, r.mpaths_per_s,
                  r.kernel_ms, r.device_mib, r.top_kernels.c_str());
    };
    if (default_only) {
      row("bounces 4 (default)", bake_once(s.value(), base, *ctx.value()));
      continue;
    }
    // Both ray-query backends side by side (accel/intersector.h); the rows
    // below use the default (auto: Embree on a CPU device).
    for (int bounces : {1, 4}) {
      auto st = base;
      st.max_bounces = bounces;
      st.intersector = accel::IntersectorKind::kEmbree;
      const Run embree = bake_once(s.value(), st, *ctx.value());
      st.intersector = accel::IntersectorKind::kOpenCl;
      const Run opencl = bake_once(s.value(), st, *ctx.value());
      row(strprintf("bounces %d, embree", bounces), embree);
      row(strprintf("bounces %d, opencl", bounces), opencl);
      std::printf("  throughput embree / opencl at %d bounces: %.2fx\n", bounces,
                  embree.mpaths_per_s / opencl.mpaths_per_s);
    }
    if (!quick) {
      for (uint32_t batch : {1u << 14, 1u << 16, 1u << 18, 1u << 20}) {
        auto st = base;
        st.paths_per_iteration = batch;
        row(strprintf("bounces 4, batch %u", batch), bake_once(s.value(), st, *ctx.value()));
      }
    }
    auto st = base;
    const Run ref = bake_once(s.value(), st, *ctx.value());
    st.compaction = false;
    const Run no_compaction = bake_once(s.value(), st, *ctx.value());
    st = base;
    st.sort_directions = true;
    const Run sorted = bake_once(s.value(), st, *ctx.value());
    row("bounces 4 (default)", ref);
    row("  compaction off", no_compaction);
    row("  direction sort on", sorted);
    std::printf("  time ratio vs default: compaction off %.2fx, direction sort on %.2fx\n\n",
                no_compaction.seconds / ref.seconds, sorted.seconds / ref.seconds);
  }
  return 0;
}
