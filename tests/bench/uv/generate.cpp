// tests/bench/uv/generate: whole-scene lightmap UV generation
// (uv/generate.h) on imported scenes with their TEXCOORD_1 stripped, on one
// core. Prints one Markdown row per scene and setting: triangles, charts, wall
// and process CPU time (charts / pack / total, best of R by total wall time),
// atlas side, UvReport efficiency, stretch L2 / Linf (the report's, and the
// final atlas's from an independent check), density spread, pages, and texel
// centres covered by two triangles in the laid-out atlas (tests/support/
// uv_layout_check.h, every instance placed). Exits 1 when generation fails or
// any texel centre overlaps.
//
//   bench_uv_generate [--resolution N | --density D] [--padding P]
//                     [--repeats R] [--max-resolution M] [SCENE...]
//   (default: --resolution 2048, the shared sponza.glb)
#include "uv/generate.h"

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "scene/gltf_import.h"
#include "support/uv_layout_check.h"

using namespace luxel;

namespace {

double cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// Generation must not see the file's lightmap UVs.
void strip_lightmap_uvs(scene::Scene* s) {
  for (scene::Mesh& m : s->meshes) {
    m.uv1.assign(m.positions.size(), Vec2{0, 0});
    m.has_lightmap_uvs = false;
    m.lightmap_uv_overlap_texels = 0;
  }
}

}  // namespace

int main(int argc, char** argv) {
  int repeats = 1, resolution = 0, padding = 2, max_resolution = 8192;
  double density = 0;
  std::vector<std::string> scenes;
  for (int i = 1; i < argc; ++i) {
    const bool has_value = i + 1 < argc;
    if (!std::strcmp(argv[i], "--repeats") && has_value)
      repeats = std::max(1, std::atoi(argv[++i]));
    else if (!std::strcmp(argv[i], "--resolution") && has_value)
      resolution = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--density") && has_value)
      density = std::atof(argv[++i]);
    else if (!std::strcmp(argv[i], "--padding") && has_value)
      padding = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--max-resolution") && has_value)
      max_resolution = std::atoi(argv[++i]);
    else if (argv[i][0] == '-') {
      std::fprintf(stderr, "bench_uv_generate: unknown option %s\n", argv[i]);
      return 2;
    } else {
      scenes.push_back(argv[i]);
    }
  }
  if (resolution == 0 && density == 0) resolution = 2048;
  if (scenes.empty()) scenes.push_back(std::string(LUXEL_SHARED_SCENES_DIR) + "/sponza.glb");

  uv::GenerateOptions options;
  options.atlas.resolution = resolution;
  options.atlas.texel_density = static_cast<float>(density);
  options.atlas.padding_texels = padding;
  options.atlas.max_resolution = max_resolution;

  std::printf(
      "| scene | triangles | setting | texels/unit | atlas | pages | charts | unplaced | "
      "charts s | pack s | total wall s | total CPU s | attempts | efficiency | stretch L2 | "
      "stretch Linf | atlas L2 | atlas Linf | density spread (report / measured) | collapsed "
      "triangles | overlapping texels |\n");
  std::printf(
      "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  bool ok = true;
  for (const std::string& path : scenes) {
    scene::ImportOptions io;
    io.require_lightmap_uvs = false;
    io.decode_textures = false;
    auto s = scene::import_gltf_file(path, io);
    if (!s) {
      std::fprintf(stderr, "bench_uv_generate: %s\n", s.status().to_string().c_str());
      return 1;
    }
    strip_lightmap_uvs(&s.value());
    size_t triangles = 0;
    for (const scene::Instance& inst : s->instances)
      triangles += s->meshes[static_cast<size_t>(inst.mesh)].triangle_count();

    double best_wall = INFINITY, best_cpu = 0;
    uv::UvReport best_report;
    Result<uv::GeneratedUvs> kept = internal_error("not run");
    for (int r = 0; r < repeats; ++r) {
      const double c0 = cpu_seconds();
      const auto t0 = std::chrono::steady_clock::now();
      auto g = uv::generate_lightmap_uvs(*s, options);
      const double wall =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const double cpu = cpu_seconds() - c0;
      if (!g) {
        std::fprintf(stderr, "bench_uv_generate: %s: %s\n", path.c_str(),
                     g.status().to_string().c_str());
        return 1;
      }
      if (wall < best_wall) {
        best_wall = wall;
        best_cpu = cpu;
        best_report = g->report;
      }
      if (r == 0) kept = std::move(g);
    }
    const uv::GeneratedUvs& g = kept.value();
    const testing::LayoutCheck check = testing::check_layout(g.scene, g.atlas);
    if (check.overlapping_texels != 0 || check.outside_triangles != 0) ok = false;
    const uv::UvReport& rep = best_report;
    char setting[64];
    if (resolution > 0)
      std::snprintf(setting, sizeof setting, "resolution %d", resolution);
    else
      std::snprintf(setting, sizeof setting, "density %g", density);
    const char* name = std::strrchr(path.c_str(), '/');
    std::printf(
        "| %s | %zu | %s | %.4g | %dx%d | 1 | %zu | %zu | %.3f | %.3f | %.3f | %.3f | %d | "
        "%.1f %% | %.4f | %.3f | %.4f | %.3f | %.3f / %.3f | %lld | %lld |\n",
        name ? name + 1 : path.c_str(), triangles, setting, g.atlas.texels_per_unit, g.atlas.width,
        g.atlas.height, rep.charts, rep.unplaced_triangles, rep.chart_seconds, rep.pack_seconds,
        best_wall, best_cpu, rep.pack_attempts, 100 * rep.efficiency, rep.stretch_l2,
        rep.stretch_linf, check.stretch_l2, check.stretch_linf, rep.density_spread,
        check.density_min > 0 ? check.density_max / check.density_min : 1.0,
        check.collapsed_triangles, check.overlapping_texels);
    if (check.outside_triangles != 0)
      std::fprintf(stderr, "bench_uv_generate: %s: %lld triangles outside the atlas\n",
                   path.c_str(), check.outside_triangles);
    std::fflush(stdout);
  }
  return ok ? 0 : 1;
}
