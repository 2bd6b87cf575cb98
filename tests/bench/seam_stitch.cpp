// Seam stitching on a finished bake: re-finds the seams of SCENE at the
// bake's resolution, reads DIR/irradiance.exr written without --seam-stitch
// (dilated, unstitched) and stitches it, printing the discontinuity before
// and after, the most negative value, and the solve's CPU seconds.
//   bench_seam_stitch SCENE DIR [--lambda L] [--padding P] [--tolerance T] [--points N]
//                     [--min-edge TEXELS] [--min-chart TEXELS] [--clamp 0|1]
//                     [--sigmas Z] [--rel-gap G] [--noise 0|1] [--pool 0|1]
//                     [--write OUT.exr]
// The defaults are the bake's: sample points whose gap exceeds Z standard
// deviations (from DIR/rel_error.exr) and G times the sides' mean are left out
// (SeamStitchOptions::structure_sigmas); --noise 0 stitches every point (as
// before that rule); --pool 0 bounds each texel's move by its own standard
// error instead of the pooled one (SeamStitchOptions::pool_move_sigmas).
// Also prints how far the stitch moved the covered texels (RMS over them and
// the channels). --write saves the stitched map (to compare
// option choices against a reference without re-baking). SEAM_DEBUG=1 also
// prints every 20th-part seam with its values, every stitched seam (those
// the narrow-chart rule keeps) and the seams around the lowest texel.
#include "output/seam_stitch.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>

#include "atlas/seams.h"
#include "bake/lightmap_layout.h"
#include "output/exr.h"
#include "scene/gltf_import.h"
#include "settings/bake_settings.h"
#include "settings/settings_schema.h"

using namespace luxel;

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s SCENE DIR [--lambda L] [--padding P] [--tolerance T]\n",
                 argv[0]);
    return 2;
  }
  output::SeamStitchOptions o;
  bool clamp = true;        // as the bake does for irradiance
  bool noise_bound = true;  // as the bake does
  std::string write_path;
  for (int i = 3; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--write") write_path = argv[i + 1];
    const double v = std::atof(argv[i + 1]);
    if (a == "--lambda") o.seam_weight = v;
    if (a == "--padding") o.padding_weight = v;
    if (a == "--tolerance") o.tolerance = v;
    if (a == "--points") o.samples_per_texel = v;
    if (a == "--min-edge") o.min_edge_texels = v;
    if (a == "--min-chart") o.min_chart_texels = v;
    if (a == "--clamp") clamp = v != 0;
    if (a == "--sigmas") o.structure_sigmas = v;
    if (a == "--rel-gap") o.structure_rel_gap = v;
    if (a == "--move") o.max_move_sigmas = v;
    if (a == "--noise") noise_bound = v != 0;
    if (a == "--pool") o.pool_move_sigmas = v != 0;
  }
  auto scene = scene::import_gltf_file(argv[1]);
  if (!scene) return std::fprintf(stderr, "%s\n", scene.status().to_string().c_str()), 1;
  auto img = output::read_exr(std::string(argv[2]) + "/irradiance.exr");
  if (!img) return std::fprintf(stderr, "%s\n", img.status().to_string().c_str()), 1;
  std::vector<float> rel_error;
  if (noise_bound) {
    auto rel = output::read_exr(std::string(argv[2]) + "/rel_error.exr");
    if (!rel) return std::fprintf(stderr, "%s\n", rel.status().to_string().c_str()), 1;
    rel_error = rel.value().pixels;  // one channel
  }
  pipeline::BakeSettings s = pipeline::default_settings();
  s.atlas.resolution = img.value().width;
  auto layout = pipeline::lay_out_lightmap(scene.value(), s);
  if (!layout) return std::fprintf(stderr, "%s\n", layout.status().to_string().c_str()), 1;
  const std::clock_t c0 = std::clock();
  const atlas::SeamSet seams = atlas::find_seams(*layout.value().scene, layout.value().atlas);
  const double find_s = double(std::clock() - c0) / CLOCKS_PER_SEC;
  std::vector<output::StitchEdge> edges;
  for (const auto& e : seams.edges)
    if (e.page == 0) edges.push_back({e.a0, e.a1, e.b0, e.b1, e.chart_texels});
  output::Image& im = img.value();
  std::vector<float> coverage(im.texel_count());
  for (size_t t = 0; t < coverage.size(); ++t) coverage[t] = im.pixels[t * 4 + 3];
  if (std::getenv("SEAM_DEBUG")) {
    auto px = [&](Vec2 p, int c) {
      const int x = std::clamp(int(p.x), 0, im.width - 1),
                y = std::clamp(int(p.y), 0, im.height - 1);
      return im.pixels[(size_t(y) * im.width + x) * 4 + c];
    };
    for (size_t i = 0; i < edges.size(); i += edges.size() / 20) {
      const auto& e = edges[i];
      const Vec2 ma{0.5f * (e.a0.x + e.a1.x), 0.5f * (e.a0.y + e.a1.y)};
      const Vec2 mb{0.5f * (e.b0.x + e.b1.x), 0.5f * (e.b0.y + e.b1.y)};
      std::printf(
          "A (%.2f,%.2f)-(%.2f,%.2f) v %.3f a %.2f | B (%.2f,%.2f)-(%.2f,%.2f) v %.3f a %.2f\n",
          e.a0.x, e.a0.y, e.a1.x, e.a1.y, px(ma, 1), px(ma, 3), e.b0.x, e.b0.y, e.b1.x, e.b1.y,
          px(mb, 1), px(mb, 3));
    }
    for (const auto& e : edges)
      if (e.chart_texels >= o.min_chart_texels)
        std::printf("stitched: chart %.2f A (%.2f,%.2f)-(%.2f,%.2f) | B (%.2f,%.2f)-(%.2f,%.2f)\n",
                    e.chart_texels, e.a0.x, e.a0.y, e.a1.x, e.a1.y, e.b0.x, e.b0.y, e.b1.x, e.b1.y);
  }
  const std::vector<float> unstitched = im.pixels;
  const std::clock_t c1 = std::clock();
  const output::SeamStitcher st(im.width, im.height, edges, coverage, o);
  const auto before = st.measure(im.pixels, 4, 0, 3);
  size_t structural = 0;
  const int it = st.stitch(im.pixels, 4, 0, 3, clamp, rel_error, &structural);
  const double stitch_s = double(std::clock() - c1) / CLOCKS_PER_SEC;
  const auto after = st.measure(im.pixels, 4, 0, 3);
  double moved_sq = 0;
  size_t moved_n = 0;
  for (size_t t = 0; t < im.texel_count(); ++t)
    if (coverage[t] > 0)
      for (int c = 0; c < 3; ++c, ++moved_n)
        moved_sq += std::pow(double(im.pixels[t * 4 + c]) - unstitched[t * 4 + c], 2);
  std::printf("moved: RMS %.4g over %zu covered texel channels\n",
              moved_n ? std::sqrt(moved_sq / moved_n) : 0.0, moved_n);
  float lowest = 0;
  size_t negative = 0;
  for (size_t t = 0; t < im.texel_count(); ++t)
    for (int c = 0; c < 3; ++c) {
      lowest = std::min(lowest, im.pixels[t * 4 + c]);
      negative += im.pixels[t * 4 + c] < 0;
    }
  if (std::getenv("SEAM_DEBUG")) {
    size_t worst = 0;
    for (size_t t = 0; t < im.texel_count(); ++t)
      if (im.pixels[t * 4 + 1] < im.pixels[worst * 4 + 1]) worst = t;
    const double wx = double(worst % im.width) + 0.5, wy = double(worst / im.width) + 0.5;
    std::printf("lowest at texel (%zu, %zu) = %.3f\n", worst % im.width, worst / im.width,
                im.pixels[worst * 4 + 1]);
    for (const auto& e : edges) {
      auto close = [&](Vec2 p, Vec2 q) {
        for (int k = 0; k <= 20; ++k) {
          const double x = p.x + k / 20.0 * (q.x - p.x), y = p.y + k / 20.0 * (q.y - p.y);
          if (std::abs(x - wx) < 1 && std::abs(y - wy) < 1) return true;
        }
        return false;
      };
      if (close(e.a0, e.a1) || close(e.b0, e.b1))
        std::printf("  A (%.2f,%.2f)-(%.2f,%.2f) | B (%.2f,%.2f)-(%.2f,%.2f)\n", e.a0.x, e.a0.y,
                    e.a1.x, e.a1.y, e.b0.x, e.b0.y, e.b1.x, e.b1.y);
    }
  }
  std::printf(
      "edges %zu (hard %zu, non-manifold %zu, cross-page %zu) points %zu unknowns %zu\n"
      "before rms_abs %.4g max_abs %.4g rms_rel %.4g max_rel %.4g\n"
      "after  rms_abs %.4g max_abs %.4g rms_rel %.4g max_rel %.4g\n"
      "cg iterations %d, find %.3f s, stitch %.3f s CPU (3 channels), lowest %.4g, negative %zu\n"
      "edges left alone: %zu short, %zu of narrow charts; points left out as structure: %zu\n",
      edges.size(), seams.hard_edges, seams.non_manifold, seams.cross_page, st.points(),
      st.unknowns(), before.rms_abs, before.max_abs, before.rms_rel, before.max_rel, after.rms_abs,
      after.max_abs, after.rms_rel, after.max_rel, it, find_s, stitch_s, lowest, negative,
      st.short_edges(), st.narrow_chart_edges(), structural);
  if (!write_path.empty()) {
    const Status w = output::write_exr(write_path, im, {"R", "G", "B", "A"});
    if (!w.ok()) return std::fprintf(stderr, "%s\n", w.to_string().c_str()), 1;
  }
  return 0;
}
