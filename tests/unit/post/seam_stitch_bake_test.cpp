// Seam stitching in a whole bake: a 4 x 4 plane whose two triangles lie in
// two charts of the file's TEXCOORD_1 (the diagonal is a seam), lit by a
// point light so the irradiance varies along the seam. The written
// irradiance.exr is read back and fetched bilinearly here, along the seam as
// this test knows it from the UVs it wrote (not from atlas::find_seams):
// with seam_stitch the gap at least halves while no covered texel moves by
// more than its standard error; texels away from the seam are bit-identical
// in both bakes.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "../scene/gltf_builder.h"
#include "bake/bake.h"
#include "device/context.h"
#include "output/exr.h"
#include "post/bake_outputs.h"
#include "scene/gltf_import.h"

namespace luxel {
namespace {

using nlohmann::json;
using test::GltfBuilder;

constexpr int kRes = 32;
// Triangle A (P0 P1 P2) and B (P0 P2 P3); the seam P0-P2 in atlas UV.
const float kUvA[3][2] = {{0.05f, 0.05f}, {0.45f, 0.05f}, {0.45f, 0.45f}};
const float kUvB[3][2] = {{0.55f, 0.05f}, {0.95f, 0.45f}, {0.55f, 0.45f}};

std::string plane_glb() {
  GltfBuilder b;
  b.add_material({{"pbrMetallicRoughness", {{"baseColorFactor", {0.5, 0.5, 0.5, 1}}}}});
  const float p[4][3] = {{-2, 0, -2}, {2, 0, -2}, {2, 0, 2}, {-2, 0, 2}};
  std::vector<float> pos, nrm, uv1;
  auto vertex = [&](int corner, const float* uv) {
    pos.insert(pos.end(), p[corner], p[corner] + 3);
    nrm.insert(nrm.end(), {0, 1, 0});
    uv1.insert(uv1.end(), {uv[0], uv[1]});
  };
  for (int k = 0; k < 3; ++k) vertex(k, kUvA[k]);                // P0 P1 P2
  for (int k = 0; k < 3; ++k) vertex((k ? k + 1 : 0), kUvB[k]);  // P0 P2 P3
  json prim;
  prim["attributes"]["POSITION"] = b.add_floats(pos, "VEC3");
  prim["attributes"]["NORMAL"] = b.add_floats(nrm, "VEC3");
  prim["attributes"]["TEXCOORD_1"] = b.add_floats(uv1, "VEC2");
  prim["indices"] = b.add_indices({0, 2, 1, 3, 5, 4});  // counter-clockwise seen from +y
  prim["material"] = 0;
  b.add_node({{"mesh", b.add_mesh("plane", {prim})}});
  b.doc["extensionsUsed"] = {"KHR_lights_punctual"};
  b.doc["extensions"]["KHR_lights_punctual"]["lights"] =
      json::array({{{"type", "point"}, {"intensity", 40}}});
  b.add_node({{"translation", {-1.0, 1.2, 1.5}},
              {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
  return b.glb();
}

double bilerp(const output::Image& img, double px, double py, int ch) {
  const double sx = px - 0.5, sy = py - 0.5;
  const int x0 = int(std::floor(sx)), y0 = int(std::floor(sy));
  const double fx = sx - x0, fy = sy - y0;
  auto t = [&](int x, int y) {
    return double(img.pixels[img.index(std::clamp(x, 0, img.width - 1),
                                       std::clamp(y, 0, img.height - 1), ch)]);
  };
  return (1 - fy) * ((1 - fx) * t(x0, y0) + fx * t(x0 + 1, y0)) +
         fy * ((1 - fx) * t(x0, y0 + 1) + fx * t(x0 + 1, y0 + 1));
}

// Largest relative gap of the green channel along the seam, 101 points.
double seam_gap(const output::Image& img) {
  double worst = 0;
  for (int k = 0; k <= 100; ++k) {
    const double t = k / 100.0;
    auto at = [&](const float uv[3][2], int i0, int i1) {
      return bilerp(img, kRes * (uv[i0][0] + t * (uv[i1][0] - uv[i0][0])),
                    kRes * (uv[i0][1] + t * (uv[i1][1] - uv[i0][1])), 1);
    };
    const double a = at(kUvA, 0, 2), b = at(kUvB, 0, 1);  // both P0 -> P2
    worst = std::max(worst, std::abs(a - b) / (0.5 * (a + b) + 1e-12));
  }
  return worst;
}

// Chebyshev distance in texels from texel (x, y)'s centre to the segment.
double distance_to_segment(int x, int y, const float p[2], const float q[2]) {
  double best = 1e30;
  for (int k = 0; k <= 200; ++k) {
    const double t = k / 200.0;
    const double sx = kRes * (p[0] + t * (q[0] - p[0])), sy = kRes * (p[1] + t * (q[1] - p[1]));
    best = std::min(best, std::max(std::abs(x + 0.5 - sx), std::abs(y + 0.5 - sy)));
  }
  return best;
}

TEST(SeamStitchBake, BothSidesOfTheSeamAgreeInTheWrittenLightmap) {
  auto ctx = device::Context::create();
  ASSERT_TRUE(ctx) << ctx.status().to_string();
  test::TempDir dir;
  auto scene = scene::import_gltf_file(dir.write("plane.glb", plane_glb()));
  ASSERT_TRUE(scene) << scene.status().to_string();
  pipeline::BakeSettings s;
  s.atlas.resolution = kRes;
  s.samples_per_texel = 16;
  s.max_bounces = 0;
  s.paths_per_iteration = 1u << 14;
  s.denoise = pipeline::Denoise::kAtrous;  // the denoised map is stitched too
  std::vector<output::Image> images, denoised;
  json manifest;
  for (bool stitch : {false, true}) {
    s.seam_stitch = stitch;
    auto r = pipeline::bake(scene.value(), s, *ctx.value());
    ASSERT_TRUE(r) << r.status().to_string();
    ASSERT_EQ(r.value().atlas.mode, atlas::AtlasMode::kShared);
    const std::string out = dir.path() + (stitch ? "/on" : "/off");
    auto written = pipeline::write_bake_outputs(out, scene.value(), s, r.value());
    ASSERT_TRUE(written) << written.status().to_string();
    auto img = output::read_exr(written.value().irradiance_exr);
    ASSERT_TRUE(img) << img.status().to_string();
    images.push_back(std::move(img.value()));
    // The denoised map is stitched too.
    ASSERT_FALSE(written.value().irradiance_denoised_exr.empty());
    auto den = output::read_exr(written.value().irradiance_denoised_exr);
    ASSERT_TRUE(den) << den.status().to_string();
    denoised.push_back(std::move(den.value()));
    std::ifstream in(out + "/manifest.json");
    manifest = json::parse(in);
    EXPECT_EQ(manifest.contains("seam_stitch"), stitch);
  }
  const double before = seam_gap(images[0]), after = seam_gap(images[1]);
  std::printf("seam gap (max relative, green): before %.4g, after %.4g\n", before, after);
  // A point light and no bounces: the 16-spp map is nearly converged, so
  // its baked texels may move by one standard error only
  // (SeamStitchOptions::max_move_sigmas) and the padding does most of the
  // joining; what remains is the part of the gap only moving baked texels
  // could close (docs/accuracy.md "Seam stitching").
  EXPECT_GT(before, 0.02);
  EXPECT_LT(after, before / 2);
  const double den_before = seam_gap(denoised[0]), den_after = seam_gap(denoised[1]);
  std::printf("denoised: before %.4g, after %.4g\n", den_before, den_after);
  EXPECT_GT(den_before, 0.02);
  EXPECT_LT(den_after, den_before / 2);
  const json& m = manifest["seam_stitch"];
  EXPECT_TRUE(m.contains("irradiance_denoised_after")) << m.dump();
  EXPECT_EQ(m["stitched_edges"], 1);
  EXPECT_LT(m["irradiance_after"]["max_rel"].get<double>(),
            m["irradiance_before"]["max_rel"].get<double>() / 2);
  // Covered texels moved by at most one standard error, pooled over the
  // texels the seam's sample points read (SeamStitchOptions::
  // pool_move_sigmas): so by no more than the largest standard error of the
  // bake's own among the covered texels within 1.5 texels of either image of
  // the seam (every bilinear footprint lies there).
  auto rel = output::read_exr(dir.path() + "/off/rel_error.exr");
  ASSERT_TRUE(rel) << rel.status().to_string();
  double largest_sigma = 0;
  for (int y = 0; y < kRes; ++y)
    for (int x = 0; x < kRes; ++x) {
      const size_t t = size_t(y) * kRes + x;
      if (!(images[0].pixels[t * 4 + 3] > 0)) continue;
      if (distance_to_segment(x, y, kUvA[0], kUvA[2]) > 1.5 &&
          distance_to_segment(x, y, kUvB[0], kUvB[1]) > 1.5)
        continue;
      double sq = 0;
      for (int c = 0; c < 3; ++c)
        sq += double(images[0].pixels[t * 4 + c]) * images[0].pixels[t * 4 + c];
      largest_sigma = std::max(largest_sigma, double(rel.value().pixels[t]) * std::sqrt(sq / 3));
    }
  ASSERT_GT(largest_sigma, 0.0);
  for (size_t t = 0; t < images[0].texel_count(); ++t) {
    if (!(images[0].pixels[t * 4 + 3] > 0)) continue;
    for (int c = 0; c < 3; ++c)
      EXPECT_LE(std::abs(images[1].pixels[t * 4 + c] - images[0].pixels[t * 4 + c]),
                largest_sigma * 1.0001 + 1e-6)
          << t;
  }
  // Away from both images of the seam (more than 1.5 texels: outside every
  // bilinear footprint), stitching changed nothing.
  size_t compared = 0;
  for (int y = 0; y < kRes; ++y)
    for (int x = 0; x < kRes; ++x) {
      if (distance_to_segment(x, y, kUvA[0], kUvA[2]) <= 1.5 ||
          distance_to_segment(x, y, kUvB[0], kUvB[1]) <= 1.5)
        continue;
      ++compared;
      for (int c = 0; c < 4; ++c)
        ASSERT_EQ(images[0].pixels[images[0].index(x, y, c)],
                  images[1].pixels[images[1].index(x, y, c)])
            << x << "," << y << "," << c;
    }
  EXPECT_GT(compared, size_t(kRes * kRes / 2));
}

}  // namespace
}  // namespace luxel
