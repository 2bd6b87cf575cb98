// The a-trous lightmap denoiser (post/denoise.h) in real bakes against
// closed forms. The scenes are lit by rectangular Lambertian emitters, whose
// irradiance on a plane has a closed form (Lambert's polygon formula) and
// whose next-event estimate is noisy at a few samples per texel:
//   (a) noise: the denoised RMSE against the closed form is well below the
//       raw RMSE, and the denoised mean over the plane stays unbiased;
//   (b) edges: two coplanar charts far apart in the world, lit very
//       differently, touch in the atlas; near their common atlas border the
//       denoised error must not exceed the raw error;
//   (c) the same check must FAIL when the filter ignores chart ids (the
//       injected error), so (b) cannot pass trivially.
#include "post/denoise.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>

#include "atlas/sample_info.h"
#include "bake/bake.h"
#include "device/context.h"
#include "kernels/shared/sample_info.h"
#include "post/denoise_guides.h"
#include "support/device_context.h"
#include "support/test_scenes.h"
#include "unit/post/lit_quads.h"

namespace luxel {
namespace {

using testing::errors;
using testing::Errors;
using testing::Expected;
using testing::expected_irradiance;
using testing::two_charts;
using testing::TwoCharts;

class DenoiseTest : public testing::DeviceTest<> {
 protected:
  static pipeline::BakeSettings settings(int resolution, uint32_t spp) {
    pipeline::BakeSettings s;
    s.atlas.resolution = resolution;
    s.samples_per_texel = spp;
    s.max_bounces = 0;  // direct light: the closed form is exact
    s.paths_per_iteration = 1u << 16;
    s.seed = 11;
    s.denoise = pipeline::Denoise::kAtrous;
    return s;
  }
};

// (a) One plane under a small emitter (irradiance peaked in the middle,
// steep towards the edges): at 4 and 16 spp the denoised RMSE is at most
// half the raw RMSE, and the denoised mean over the plane is within 2 % of
// the raw mean (measured: +1.1 % at 4 spp, +0.6 % at 16; the filter's
// weights are normalised per output texel, not per input, so a peaked field
// gains a little) and within 3 % of the closed form's.
TEST_F(DenoiseTest, LowersErrorAgainstClosedFormWithoutBias) {
  TwoCharts t = two_charts(1.0f, 1.0f, 0.5f);
  // Only the first lit quad.
  t.scene.meshes.resize(2);
  t.scene.instances.resize(2);
  for (uint32_t spp : {4u, 16u}) {
    const auto st = settings(64, spp);
    auto r = pipeline::bake(t.scene, st, *ctx_);
    ASSERT_TRUE(r) << r.status().to_string();
    ASSERT_EQ(r.value().irradiance_denoised.size(), r.value().irradiance.size());
    auto info = atlas::build_sample_info(t.scene, r.value().atlas);
    ASSERT_TRUE(info);
    const Expected ex = expected_irradiance(t, r.value().atlas, info.value(), 1);
    auto all = [](uint32_t) { return true; };
    const Errors raw = errors(r.value().irradiance, ex, all);
    const Errors dn = errors(r.value().irradiance_denoised, ex, all);
    std::printf(
        "  %u spp: %zu texels, RMSE raw %.4f denoised %.4f, mean ratio raw %.5f "
        "denoised %.5f\n",
        spp, raw.texels, raw.rmse, dn.rmse, raw.mean_ratio, dn.mean_ratio);
    ASSERT_GT(raw.texels, 1500u);
    EXPECT_LT(dn.rmse, 0.5 * raw.rmse);
    EXPECT_NEAR(dn.mean_ratio / raw.mean_ratio, 1.0, 0.02);
    EXPECT_NEAR(dn.mean_ratio, 1.0, 0.03);
  }
}

// (b) + (c): texels within 3 texels of the atlas border between the two
// charts. Large emitters make each plane's irradiance nearly flat; chart 1
// is 1.5x brighter (a step the luminance weight alone lets through at 16 spp)
// and coplanar with chart 0 (so only the chart id tells them apart: the
// tangent-plane and normal guides agree).
TEST_F(DenoiseTest, DoesNotBlurAcrossChartBorders) {
  TwoCharts t = two_charts(1.5f, 8.0f, 1.0f);
  const int res = 64;
  const auto st = settings(res, 16);
  auto r = pipeline::bake(t.scene, st, *ctx_);
  ASSERT_TRUE(r) << r.status().to_string();
  const pipeline::BakeResult& b = r.value();
  auto info = atlas::build_sample_info(t.scene, b.atlas);
  ASSERT_TRUE(info);
  const Expected ex = expected_irradiance(t, b.atlas, info.value(), 2);
  // Column of the border: u = 0.5.
  auto near_border = [&](uint32_t texel) {
    const int x = int(texel % uint32_t(res));
    return std::abs(2 * x + 1 - res) <= 2 * 3;
  };
  const Errors raw = errors(b.irradiance, ex, near_border);
  const Errors dn = errors(b.irradiance_denoised, ex, near_border);

  // The injected error: the same filter, but every texel in one chart.
  auto guides = pipeline::build_denoise_guides(t.scene, b.atlas, info.value());
  auto denoiser = pipeline::Denoiser::create(*ctx_, guides);
  ASSERT_TRUE(denoiser) << denoiser.status().to_string();
  const auto variance = pipeline::texel_variance(b.irradiance, b.rel_error);
  auto same = denoiser.value()->run(b.irradiance, variance, pipeline::DenoiseParams{});
  ASSERT_TRUE(same);
  EXPECT_EQ(same.value(), b.irradiance_denoised) << "the bake's filter is the default one";
  pipeline::DenoiseParams blind;
  blind.ignore_charts = true;
  auto mixed = denoiser.value()->run(b.irradiance, variance, blind);
  ASSERT_TRUE(mixed);
  // The comparison: the charts' outer edges (3 texel columns at either
  // side of the atlas), where the filter's support is one-sided too but
  // there is no other chart beside them.
  auto interior = [&](uint32_t texel) {
    const int x = int(texel % uint32_t(res));
    return x < 3 || x >= res - 3;
  };
  const Errors bad = errors(mixed.value(), ex, near_border);
  const Errors dn_inside = errors(b.irradiance_denoised, ex, interior);
  const Errors bad_inside = errors(mixed.value(), ex, interior);
  std::printf(
      "  near the border (%zu texels): RMSE raw %.4f, denoised %.4f, ignoring charts %.4f\n"
      "  outer edges (%zu texels): denoised %.4f, ignoring charts %.4f\n",
      raw.texels, raw.rmse, dn.rmse, bad.rmse, dn_inside.texels, dn_inside.rmse, bad_inside.rmse);
  ASSERT_GT(raw.texels, 200u);
  ASSERT_GT(dn_inside.texels, 250u);
  // The edge check: near the border the filter is no worse than the raw
  // bake, and no worse than 1.5x its own error at the outer edges (a blur
  // across the border shows as a band of error along it).
  auto edge_ok = [&](const Errors& edge, const Errors& inside) {
    return edge.rmse <= raw.rmse && edge.rmse <= 1.5 * inside.rmse;
  };
  EXPECT_TRUE(edge_ok(dn, dn_inside)) << "the filter must not blur across the chart border";
  EXPECT_FALSE(edge_ok(bad, bad_inside)) << "ignoring chart ids must be detected";
}

// Chart labels: the two triangles of a quad share UVs (one chart); quads
// whose UV corners are distinct are separate charts.
TEST(DenoiseGuides, LabelsChartsByUvConnectivity) {
  scene::Scene s;
  s.materials.push_back(testing::diffuse_material(0.5f));
  testing::add_quad(s, {0, 0, 0}, {1, 0, 0}, {0, 0, 1}, 0, 0, 0.4f, 0.4f, 0);
  scene::Mesh m = s.meshes[0];
  const scene::Mesh other = [&] {
    scene::Scene t;
    testing::add_quad(t, {5, 0, 0}, {1, 0, 0}, {0, 0, 1}, 0.5f, 0.5f, 0.9f, 0.9f, 0);
    return t.meshes[0];
  }();
  // One mesh of two disjoint quads.
  for (uint32_t i : other.indices) m.indices.push_back(i + 4);
  m.positions.insert(m.positions.end(), other.positions.begin(), other.positions.end());
  m.uv1.insert(m.uv1.end(), other.uv1.begin(), other.uv1.end());
  std::vector<uint32_t> charts;
  EXPECT_EQ(pipeline::label_uv_charts(m, charts), 2u);
  EXPECT_EQ(charts, (std::vector<uint32_t>{0, 0, 1, 1}));
}

}  // namespace
}  // namespace luxel
