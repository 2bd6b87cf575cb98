// tests/bench/uv/charts: chart segmentation and parametrization (uv/charts.h)
// over every mesh of a scene, on one core. Prints triangles, charts (planar /
// LSCM / splits), time, and Sander stretch (area-weighted mean L2 over the
// scene, worst chart L2 and Linf).
//
//   bench_uv_charts [--repeats R] [SCENE...]   (default: the shared sponza.glb)
#include "uv/charts.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "scene/gltf_import.h"
#include "uv/stretch.h"
#include "uv/validate.h"

using namespace luxel;

int main(int argc, char** argv) {
  int repeats = 3;
  std::vector<std::string> scenes;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--repeats") && i + 1 < argc)
      repeats = std::max(1, std::atoi(argv[++i]));
    else
      scenes.push_back(argv[i]);
  }
  if (scenes.empty()) scenes.push_back(std::string(LUXEL_SHARED_SCENES_DIR) + "/sponza.glb");

  std::printf(
      "| scene | meshes | triangles | degenerate | charts | planar | LSCM | rejected splits | "
      "aspect splits | stretch splits | time s (best of %d) | L2 mean | L2 max chart | Linf max "
      "chart | invalid charts |\n",
      repeats);
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const std::string& path : scenes) {
    scene::ImportOptions io;
    io.require_lightmap_uvs = false;
    io.decode_textures = false;
    auto s = scene::import_gltf_file(path, io);
    if (!s) {
      std::fprintf(stderr, "bench_uv_charts: %s\n", s.status().to_string().c_str());
      return 1;
    }
    double best = INFINITY;
    uv::ChartStats total;
    double l2_sum = 0, area = 0, l2_max = 0, linf_max = 0;
    size_t invalid = 0;  // charts validate_chart rejects: must be 0
    for (int r = 0; r < repeats; ++r) {
      uv::ChartStats sum;
      std::vector<std::vector<uv::Chart>> all;
      const auto t0 = std::chrono::steady_clock::now();
      for (const scene::Mesh& m : s->meshes) {
        uv::ChartStats st;
        auto c = uv::build_charts(m, {}, &st);
        if (!c) {
          std::fprintf(stderr, "bench_uv_charts: %s\n", c.status().to_string().c_str());
          return 1;
        }
        sum.triangles += st.triangles;
        sum.degenerate_triangles += st.degenerate_triangles;
        sum.charts += st.charts;
        sum.planar_charts += st.planar_charts;
        sum.lscm_charts += st.lscm_charts;
        sum.rejected_splits += st.rejected_splits;
        sum.aspect_splits += st.aspect_splits;
        sum.stretch_splits += st.stretch_splits;
        all.push_back(std::move(c.value()));
      }
      const double sec =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      best = std::min(best, sec);
      if (r == 0) {
        total = sum;
        for (size_t i = 0; i < all.size(); ++i)
          for (const uv::Chart& c : all[i]) {
            if (uv::validate_chart(c) != uv::ChartDefect::kNone) ++invalid;
            const uv::Stretch st = uv::chart_stretch(s->meshes[i], c);
            l2_sum += st.l2 * st.l2 * st.area_3d;
            area += st.area_3d;
            l2_max = std::max(l2_max, st.l2);
            linf_max = std::max(linf_max, st.linf);
          }
      }
    }
    const char* name = std::strrchr(path.c_str(), '/');
    std::printf(
        "| %s | %zu | %zu | %zu | %zu | %zu | %zu | %zu | %zu | %zu | %.3f | %.4f | %.3f | %.3f | "
        "%zu |\n",
        name ? name + 1 : path.c_str(), s->meshes.size(), total.triangles,
        total.degenerate_triangles, total.charts, total.planar_charts, total.lscm_charts,
        total.rejected_splits, total.aspect_splits, total.stretch_splits, best,
        area > 0 ? std::sqrt(l2_sum / area) : 1.0, l2_max, linf_max, invalid);
  }
  return 0;
}
