// Device-memory tiling (bake/tile_plan.h): a bake forced into tiles by a
// small budget gives the bits of the untiled bake under the samples rule
// (per-texel sequences depend only on texel, sample index and seed), the
// other stopping rules stay correct, and a request that cannot be tiled
// fails with an error that names the budget and the reason. Bit-identity to
// the untiled bake holds for uniform sampling; with adaptive sampling each
// tile allocates its own paths by its own texels' errors, so a tiled
// adaptive bake is checked against itself (resume, stopping rule).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>

#include "bake/bake.h"
#include "device/context.h"
#include "shards/checkpoint.h"
#include "support/device_context.h"
#include "support/test_scenes.h"

namespace luxel {
namespace {

class TiledBakeTest : public testing::DeviceTest<> {
 protected:
  static pipeline::BakeSettings settings() {
    pipeline::BakeSettings s;
    s.atlas.resolution = 48;
    s.samples_per_texel = 12;
    s.max_bounces = 2;
    s.paths_per_iteration = 4096;  // several iterations per tile
    s.seed = 3;
    s.encodings.names = {"sg12", "sh2"};
    s.adaptive = false;  // uniform: the tiles' bits equal the untiled bake's
    // Traced: a tile's radiance cache gathers from its own texels only, so
    // cached tiles differ from the untiled bake by design (their own test
    // below).
    s.radiance_cache = false;
    return s;
  }
  // A budget that leaves room for about a quarter of the per-texel state.
  static double tight_budget_mib(const pipeline::BakeResult& untiled) {
    const double per_slot = 57.0 + static_cast<double>(untiled.basis_bytes_per_texel);
    const double state = per_slot * static_cast<double>(untiled.covered_texels);
    return (static_cast<double>(untiled.peak_device_bytes) - 0.75 * state) / 1048576.0;
  }
};

void expect_same_bits(const std::vector<float>& a, const std::vector<float>& b, const char* what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(float))) << what;
}

TEST_F(TiledBakeTest, TilesGiveTheBitsOfTheUntiledBake) {
  const scene::Scene scene = testing::furnace_box(0.5f, 0.25f);
  auto untiled = pipeline::bake(scene, settings(), *ctx_);
  ASSERT_TRUE(untiled) << untiled.status().to_string();
  ASSERT_EQ(untiled.value().tiles, 1u);

  pipeline::BakeSettings s = settings();
  s.device_memory_budget_mib = tight_budget_mib(untiled.value());
  auto tiled = pipeline::bake(scene, s, *ctx_);
  ASSERT_TRUE(tiled) << tiled.status().to_string();
  const pipeline::BakeResult& u = untiled.value();
  const pipeline::BakeResult& t = tiled.value();
  EXPECT_GE(t.tiles, 3u);
  EXPECT_LT(t.peak_device_bytes, u.peak_device_bytes);
  EXPECT_LE(t.peak_device_bytes, t.device_memory_budget);
  expect_same_bits(u.irradiance, t.irradiance, "irradiance");
  expect_same_bits(u.samples, t.samples, "samples");
  expect_same_bits(u.rel_error, t.rel_error, "rel_error");
  ASSERT_EQ(u.encodings.size(), t.encodings.size());
  for (size_t k = 0; k < u.encodings.size(); ++k) {
    expect_same_bits(u.encodings[k].coefficients, t.encodings[k].coefficients,
                     u.encodings[k].name.c_str());
    EXPECT_EQ(u.encodings[k].residual_rms, t.encodings[k].residual_rms);
  }
  EXPECT_EQ(u.paths, t.paths);
  EXPECT_EQ(u.nonfinite_dropped, t.nonfinite_dropped);
  EXPECT_EQ(t.min_spp, 12u);
  EXPECT_NEAR(t.error, u.error, 1e-6);
  EXPECT_EQ(t.termination, pipeline::Termination::kSamples);
}

// Checkpoints of a tiled bake hold the whole atlas (finished tiles, the
// current one, zeros after it); resuming from one in a later tile gives the
// bits of the uninterrupted bake.
TEST_F(TiledBakeTest, ResumeInALaterTileIsBitIdentical) {
  const scene::Scene scene = testing::furnace_box(0.5f, 0.25f);
  auto untiled = pipeline::bake(scene, settings(), *ctx_);
  ASSERT_TRUE(untiled);
  pipeline::BakeSettings s = settings();
  s.device_memory_budget_mib = tight_budget_mib(untiled.value());
  std::vector<pipeline::BakeCheckpoint> checkpoints;
  pipeline::BakeHooks hooks;
  hooks.fingerprint = "tiled";
  hooks.checkpoint_interval_s = 1e-9;  // after every iteration
  hooks.on_checkpoint = [&](const pipeline::BakeCheckpoint& c) { checkpoints.push_back(c); };
  auto tiled = pipeline::bake(scene, s, *ctx_, hooks);
  ASSERT_TRUE(tiled) << tiled.status().to_string();
  ASSERT_GE(tiled.value().tiles, 3u);
  expect_same_bits(untiled.value().irradiance, tiled.value().irradiance, "irradiance");

  // A checkpoint inside a later tile, through a file.
  const pipeline::BakeCheckpoint* pick = nullptr;
  for (const auto& c : checkpoints)
    if (!pick && !c.tile.empty() && c.tile[pipeline::kTileIndex] >= 1 && c.paths_done > 0)
      pick = &c;
  ASSERT_NE(pick, nullptr);
  const std::string path = ::testing::TempDir() + "/luxel_tiled.ckpt";
  ASSERT_TRUE(pipeline::write_checkpoint(path, *pick).is_ok());
  auto loaded = pipeline::read_checkpoint(path);
  ASSERT_TRUE(loaded) << loaded.status().to_string();
  pipeline::BakeHooks resume;
  resume.fingerprint = "tiled";
  resume.resume = &loaded.value();
  auto resumed = pipeline::bake(scene, s, *ctx_, resume);
  ASSERT_TRUE(resumed) << resumed.status().to_string();
  const pipeline::BakeResult& u = untiled.value();
  const pipeline::BakeResult& r = resumed.value();
  expect_same_bits(u.irradiance, r.irradiance, "irradiance");
  expect_same_bits(u.samples, r.samples, "samples");
  for (size_t k = 0; k < u.encodings.size(); ++k)
    expect_same_bits(u.encodings[k].coefficients, r.encodings[k].coefficients,
                     u.encodings[k].name.c_str());
  EXPECT_EQ(u.paths, r.paths);
  EXPECT_EQ(u.nonfinite_dropped, r.nonfinite_dropped);

  // Under another tile plan the checkpoint is refused, naming the budget.
  pipeline::BakeSettings other = settings();
  auto refused = pipeline::bake(scene, other, *ctx_, resume);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.status().message().find("device_memory_budget_mib"), std::string::npos)
      << refused.status().message();
}

// The radiance cache (and guiding) in tiles: a tile gathers only from its own texels
// (the others' caches are not on the device), so a tiled cached bake has
// other bits than an untiled one; resuming inside a later tile still gives
// the uninterrupted tiled bake's bits (the checkpoint carries the current
// tile's cache).
TEST_F(TiledBakeTest, RadianceCacheTilesResumeBitIdentically) {
  const scene::Scene scene = testing::furnace_box(0.5f, 0.25f);
  pipeline::BakeSettings s = settings();
  s.radiance_cache = true;
  s.guiding = true;           // its histograms are per texel too, checkpointed alike
  s.encodings.names.clear();  // guiding is for irradiance lightmaps
  s.samples_per_texel = 48;   // three guiding epochs
  auto untiled = pipeline::bake(scene, s, *ctx_);
  ASSERT_TRUE(untiled) << untiled.status().to_string();
  s.device_memory_budget_mib = tight_budget_mib(untiled.value());
  std::vector<pipeline::BakeCheckpoint> checkpoints;
  pipeline::BakeHooks hooks;
  hooks.fingerprint = "tiled-cache";
  hooks.checkpoint_interval_s = 1e-9;  // after every iteration
  hooks.on_checkpoint = [&](const pipeline::BakeCheckpoint& c) { checkpoints.push_back(c); };
  auto tiled = pipeline::bake(scene, s, *ctx_, hooks);
  ASSERT_TRUE(tiled) << tiled.status().to_string();
  ASSERT_GE(tiled.value().tiles, 2u);
  const pipeline::BakeCheckpoint* pick = nullptr;
  for (const auto& c : checkpoints)
    if (!pick && !c.tile.empty() && c.tile[pipeline::kTileIndex] >= 1 && c.paths_done > 0 &&
        std::any_of(c.radiance_cache.begin(), c.radiance_cache.end(),
                    [](const cl::float4& m) { return m.w >= 1.0f; }))
      pick = &c;
  ASSERT_NE(pick, nullptr) << "no checkpoint in a later tile with a filled cache";
  ASSERT_EQ(pick->radiance_cache.size(), pick->mean.size());
  ASSERT_EQ(pick->guide.size(), pick->mean.size() * pipeline::kGuideStride);
  const std::string path = ::testing::TempDir() + "/luxel_tiled_cache.ckpt";
  ASSERT_TRUE(pipeline::write_checkpoint(path, *pick).is_ok());
  auto loaded = pipeline::read_checkpoint(path);
  ASSERT_TRUE(loaded) << loaded.status().to_string();
  pipeline::BakeHooks resume;
  resume.fingerprint = "tiled-cache";
  resume.resume = &loaded.value();
  auto resumed = pipeline::bake(scene, s, *ctx_, resume);
  ASSERT_TRUE(resumed) << resumed.status().to_string();
  expect_same_bits(tiled.value().irradiance, resumed.value().irradiance, "irradiance");
  EXPECT_EQ(tiled.value().paths, resumed.value().paths);
}

// Adaptive sampling in tiles: each tile warms up, then allocates by its own
// texels' errors; resuming inside a later tile gives the uninterrupted
// tiled bake's bits, and the samples rule holds per tile (the mean).
TEST_F(TiledBakeTest, AdaptiveTilesResumeBitIdentically) {
  const scene::Scene scene = testing::furnace_box(0.5f, 0.25f);
  pipeline::BakeSettings s = settings();
  s.adaptive = true;
  s.samples_per_texel = 24;
  s.encodings.names.clear();
  auto untiled = pipeline::bake(scene, s, *ctx_);
  ASSERT_TRUE(untiled) << untiled.status().to_string();
  s.device_memory_budget_mib = tight_budget_mib(untiled.value());
  std::vector<pipeline::BakeCheckpoint> checkpoints;
  pipeline::BakeHooks hooks;
  hooks.fingerprint = "tiled-adaptive";
  hooks.checkpoint_interval_s = 1e-9;  // after every iteration
  hooks.on_checkpoint = [&](const pipeline::BakeCheckpoint& c) { checkpoints.push_back(c); };
  auto tiled = pipeline::bake(scene, s, *ctx_, hooks);
  ASSERT_TRUE(tiled) << tiled.status().to_string();
  const pipeline::BakeResult& t = tiled.value();
  ASSERT_GE(t.tiles, 3u);
  EXPECT_EQ(t.paths, uint64_t{24} * t.covered_texels);
  EXPECT_GE(t.min_spp, 8u);
  // The last checkpoint of a later tile past its warm-up.
  const pipeline::BakeCheckpoint* pick = nullptr;
  for (const auto& c : checkpoints) {
    if (c.tile.empty() || c.tile[pipeline::kTileIndex] < 1) continue;
    const double slots = c.tile[pipeline::kTileEnd] - c.tile[pipeline::kTileBegin];
    if (double(c.paths_done) > 8 * slots && double(c.paths_done) < 24 * slots) pick = &c;
  }
  ASSERT_NE(pick, nullptr);
  pipeline::BakeHooks resume;
  resume.fingerprint = "tiled-adaptive";
  resume.resume = pick;
  auto resumed = pipeline::bake(scene, s, *ctx_, resume);
  ASSERT_TRUE(resumed) << resumed.status().to_string();
  expect_same_bits(t.irradiance, resumed.value().irradiance, "irradiance");
  expect_same_bits(t.samples, resumed.value().samples, "samples");
  EXPECT_EQ(t.paths, resumed.value().paths);
}

// Progress over a tiled bake covers the whole atlas: paths only grow, and
// texels of tiles not yet baked count (min spp 0) until the last tile.
TEST_F(TiledBakeTest, ProgressAndTargetErrorCoverEveryTile) {
  const scene::Scene scene = testing::furnace_box(0.5f, 0.25f);
  auto untiled = pipeline::bake(scene, settings(), *ctx_);
  ASSERT_TRUE(untiled);
  pipeline::BakeSettings s = settings();
  s.device_memory_budget_mib = tight_budget_mib(untiled.value());
  s.samples_per_texel = 0;
  s.target_error = 0.08;
  s.time_budget_s = 120;  // a safety net only
  uint64_t last_paths = 0;
  bool monotone = true;
  auto tiled = pipeline::bake(scene, s, *ctx_, [&](const pipeline::BakeProgress& p) {
    monotone = monotone && p.paths >= last_paths;
    last_paths = p.paths;
    return true;
  });
  ASSERT_TRUE(tiled) << tiled.status().to_string();
  EXPECT_GE(tiled.value().tiles, 3u);
  EXPECT_TRUE(monotone);
  EXPECT_EQ(tiled.value().termination, pipeline::Termination::kError);
  EXPECT_LE(tiled.value().error, 0.08);
  EXPECT_GT(tiled.value().min_spp, 0u) << "every tile was baked";
}

TEST_F(TiledBakeTest, UntileableOverBudgetRequestIsAClearError) {
  const scene::Scene scene = testing::furnace_box(0.5f, 0.25f);
  auto untiled = pipeline::bake(scene, settings(), *ctx_);
  ASSERT_TRUE(untiled);
  pipeline::BakeSettings s = settings();
  s.filter = pipeline::Filter::kGaussian;
  s.device_memory_budget_mib = tight_budget_mib(untiled.value());
  auto r = pipeline::bake(scene, s, *ctx_);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().code(), StatusCode::kResourceExhausted) << r.status().to_string();
  EXPECT_NE(r.status().message().find("device_memory_budget_mib"), std::string::npos)
      << r.status().message();
  EXPECT_NE(r.status().message().find("gaussian"), std::string::npos) << r.status().message();

  // A budget below the fixed memory (scene, BVH, path state) cannot be
  // helped by tiles either.
  s.filter = pipeline::Filter::kBox;
  s.device_memory_budget_mib = 0.05;
  r = pipeline::bake(scene, s, *ctx_);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().code(), StatusCode::kResourceExhausted);
  EXPECT_NE(r.status().message().find("paths_per_iteration"), std::string::npos)
      << r.status().message();
}

}  // namespace
}  // namespace luxel
