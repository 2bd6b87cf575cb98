// Bake control for long-running hosts: checkpoints (written, read back and
// resumed bit-identically), snapshots, cancellation.
#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "device/context.h"
#include "pipeline/bake.h"
#include "pipeline/checkpoint.h"
#include "test_scenes.h"

namespace luxel {
namespace {

class BakeControlTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    auto ctx = device::Context::create();
    ASSERT_TRUE(ctx) << ctx.status().to_string();
    ctx_ = ctx.value().release();
  }
  static void TearDownTestSuite() { delete ctx_; }
  static pipeline::BakeSettings settings() {
    pipeline::BakeSettings s;
    s.atlas.resolution = 16;
    s.samples_per_texel = 64;
    s.max_bounces = 3;
    s.paths_per_iteration = 4096;  // several iterations
    return s;
  }
  static device::Context* ctx_;
};
device::Context* BakeControlTest::ctx_ = nullptr;

TEST_F(BakeControlTest, ResumeFromCheckpointIsBitIdentical) {
  const scene::Scene scene = testing::furnace_box(0.5f, 0.25f);
  auto full = pipeline::bake(scene, settings(), *ctx_);
  ASSERT_TRUE(full) << full.status().to_string();

  std::vector<pipeline::BakeCheckpoint> checkpoints;
  pipeline::BakeHooks hooks;
  hooks.fingerprint = "furnace";
  hooks.checkpoint_interval_s = 1e-9;  // after every iteration
  hooks.on_checkpoint = [&](const pipeline::BakeCheckpoint& c) { checkpoints.push_back(c); };
  auto again = pipeline::bake(scene, settings(), *ctx_, hooks);
  ASSERT_TRUE(again);
  ASSERT_GE(checkpoints.size(), 3u);
  EXPECT_EQ(0, std::memcmp(full.value().irradiance.data(), again.value().irradiance.data(),
                           full.value().irradiance.size() * 4));

  // Round trip through a file, then resume from an early checkpoint.
  const std::string path = ::testing::TempDir() + "/luxel_test.ckpt";
  ASSERT_TRUE(pipeline::write_checkpoint(path, checkpoints[1]).is_ok());
  auto loaded = pipeline::read_checkpoint(path);
  ASSERT_TRUE(loaded) << loaded.status().to_string();
  EXPECT_EQ(loaded.value().paths_done, checkpoints[1].paths_done);
  pipeline::BakeHooks resume;
  resume.fingerprint = "furnace";
  resume.resume = &loaded.value();
  auto resumed = pipeline::bake(scene, settings(), *ctx_, resume);
  ASSERT_TRUE(resumed) << resumed.status().to_string();
  EXPECT_EQ(resumed.value().paths, full.value().paths);
  EXPECT_EQ(0, std::memcmp(full.value().irradiance.data(), resumed.value().irradiance.data(),
                           full.value().irradiance.size() * 4))
      << "a resumed bake must produce the same bits as an uninterrupted one";

  // Another fingerprint is refused.
  resume.fingerprint = "other";
  EXPECT_FALSE(pipeline::bake(scene, settings(), *ctx_, resume));
}

TEST_F(BakeControlTest, ResumeKeepsDirectionalEncodingsBitIdentical) {
  const scene::Scene scene = testing::furnace_box(0.5f, 0.25f);
  pipeline::BakeSettings st = settings();
  st.encodings.names = {"sh2", "sg6", "ambient-dice9"};
  auto full = pipeline::bake(scene, st, *ctx_);
  ASSERT_TRUE(full) << full.status().to_string();
  ASSERT_EQ(full.value().encodings.size(), 3u);

  std::vector<pipeline::BakeCheckpoint> checkpoints;
  pipeline::BakeHooks hooks;
  hooks.fingerprint = "furnace-enc";
  hooks.checkpoint_interval_s = 1e-9;
  hooks.on_checkpoint = [&](const pipeline::BakeCheckpoint& c) { checkpoints.push_back(c); };
  ASSERT_TRUE(pipeline::bake(scene, st, *ctx_, hooks));
  ASSERT_GE(checkpoints.size(), 3u);
  EXPECT_FALSE(checkpoints[1].basis.empty());
  const std::string path = ::testing::TempDir() + "/luxel_test_enc.ckpt";
  ASSERT_TRUE(pipeline::write_checkpoint(path, checkpoints[1]).is_ok());
  auto loaded = pipeline::read_checkpoint(path);
  ASSERT_TRUE(loaded) << loaded.status().to_string();
  EXPECT_EQ(loaded.value().basis.size(), checkpoints[1].basis.size());
  pipeline::BakeHooks resume;
  resume.fingerprint = "furnace-enc";
  resume.resume = &loaded.value();
  auto resumed = pipeline::bake(scene, st, *ctx_, resume);
  ASSERT_TRUE(resumed) << resumed.status().to_string();
  for (size_t k = 0; k < 3; ++k)
    EXPECT_EQ(full.value().encodings[k].coefficients, resumed.value().encodings[k].coefficients)
        << full.value().encodings[k].name << ": a resumed bake must give the same coefficients";

  // A checkpoint without the basis state cannot resume a bake that has one.
  pipeline::BakeCheckpoint stripped = loaded.value();
  stripped.basis.clear();
  resume.resume = &stripped;
  EXPECT_FALSE(pipeline::bake(scene, st, *ctx_, resume));
}

TEST_F(BakeControlTest, CorruptCheckpointsAreRefused) {
  const std::string path = ::testing::TempDir() + "/luxel_corrupt.ckpt";
  pipeline::BakeCheckpoint c;
  c.width = c.height = 2;
  c.mean.resize(4);
  c.m2.resize(4);
  c.weight.resize(4);
  c.spp.resize(4);
  ASSERT_TRUE(pipeline::write_checkpoint(path, c).is_ok());
  ASSERT_TRUE(pipeline::read_checkpoint(path));
  const auto size = std::filesystem::file_size(path);
  std::filesystem::resize_file(path, size / 2);
  auto torn = pipeline::read_checkpoint(path);
  ASSERT_FALSE(torn);
  EXPECT_EQ(torn.status().code(), StatusCode::kDataLoss);
  EXPECT_EQ(pipeline::read_checkpoint(path + ".missing").status().code(), StatusCode::kNotFound);
}

TEST_F(BakeControlTest, SnapshotsAndCancellation) {
  const scene::Scene scene = testing::furnace_box(0.5f, 0.25f);
  std::atomic<bool> cancel{false};
  int snapshots = 0;
  pipeline::BakeHooks hooks;
  hooks.snapshot_interval_s = 1e-9;
  hooks.on_snapshot = [&](const pipeline::BakeSnapshot& s) {
    ++snapshots;
    EXPECT_EQ(s.irradiance.size(), size_t(s.width) * s.height * 4);
    EXPECT_GT(s.progress.paths, 0u);
    if (snapshots == 2) cancel = true;
  };
  hooks.cancel = &cancel;
  auto r = pipeline::bake(scene, settings(), *ctx_, hooks);
  ASSERT_TRUE(r);
  EXPECT_EQ(r.value().termination, pipeline::Termination::kCancelled);
  EXPECT_EQ(snapshots, 2);
  EXPECT_LT(r.value().paths, 64u * r.value().covered_texels);
}

}  // namespace
}  // namespace luxel
