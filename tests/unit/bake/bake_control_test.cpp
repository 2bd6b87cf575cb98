// Bake control for long-running hosts: checkpoints (written, read back and
// resumed bit-identically), snapshots, cancellation.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>

#include "bake/bake.h"
#include "device/context.h"
#include "output/exr.h"
#include "shards/checkpoint.h"
#include "support/device_context.h"
#include "support/test_scenes.h"

namespace luxel {
namespace {

class BakeControlTest : public testing::DeviceTest<> {
 protected:
  static pipeline::BakeSettings settings() {
    pipeline::BakeSettings s;
    s.atlas.resolution = 16;
    s.samples_per_texel = 64;
    s.max_bounces = 3;
    s.paths_per_iteration = 4096;  // several iterations
    return s;
  }
};

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

// The radiance cache (kernels/bake/radiance_cache.h) and first-bounce
// guiding (kernels/bake/guiding.h) are state the next iteration reads: the
// checkpoint carries both (version 5), so a resumed bake gives the same
// bits. Without that state the resumed bake is valid but other (it starts
// learning again), which shows the state is what matters.
TEST_F(BakeControlTest, LearnedStateResumesBitIdentically) {
  const scene::Scene scene = testing::furnace_box(0.5f, 0.25f);
  for (const bool guiding : {false, true}) {
    SCOPED_TRACE(guiding ? "guiding" : "radiance cache");
    pipeline::BakeSettings s = settings();
    s.radiance_cache = !guiding;
    s.guiding = guiding;
    s.paths_per_iteration = 1024;  // nine iterations
    auto full = pipeline::bake(scene, s, *ctx_);
    ASSERT_TRUE(full) << full.status().to_string();
    ASSERT_NE(full.value().features.find(guiding ? "guiding" : "radiance_cache"),
              std::string::npos);

    std::vector<pipeline::BakeCheckpoint> checkpoints;
    pipeline::BakeHooks hooks;
    hooks.fingerprint = "learned";
    hooks.checkpoint_interval_s = 1e-9;  // after every iteration
    hooks.on_checkpoint = [&](const pipeline::BakeCheckpoint& c) { checkpoints.push_back(c); };
    ASSERT_TRUE(pipeline::bake(scene, s, *ctx_, hooks));
    ASSERT_GE(checkpoints.size(), 6u);
    // Past the first epoch of 16 samples per texel, so the guide is frozen.
    const pipeline::BakeCheckpoint& mid = checkpoints[4];
    if (guiding) {
      ASSERT_EQ(mid.guide.size(), mid.mean.size() * pipeline::kGuideStride);
      EXPECT_TRUE(std::any_of(mid.guide.begin(), mid.guide.end(), [](const cl::float4& h) {
        return h.x > 0.0f;
      })) << "the texels learned";
    } else {
      ASSERT_EQ(mid.radiance_cache.size(), mid.mean.size());
      EXPECT_TRUE(std::any_of(mid.radiance_cache.begin(), mid.radiance_cache.end(),
                              [](const cl::float4& c) { return c.w >= 1.0f; }))
          << "the feeders filled the cache";
    }

    const std::string path = ::testing::TempDir() + "/luxel_learned.ckpt";
    ASSERT_TRUE(pipeline::write_checkpoint(path, mid).is_ok());
    auto loaded = pipeline::read_checkpoint(path);
    ASSERT_TRUE(loaded) << loaded.status().to_string();
    ASSERT_EQ(loaded.value().radiance_cache.size(), mid.radiance_cache.size());
    ASSERT_EQ(loaded.value().guide.size(), mid.guide.size());
    pipeline::BakeHooks resume;
    resume.fingerprint = "learned";
    resume.resume = &loaded.value();
    auto resumed = pipeline::bake(scene, s, *ctx_, resume);
    ASSERT_TRUE(resumed) << resumed.status().to_string();
    const auto& f = full.value().irradiance;
    EXPECT_EQ(0, std::memcmp(f.data(), resumed.value().irradiance.data(), f.size() * 4))
        << "a resumed bake must produce the same bits as an uninterrupted one";

    pipeline::BakeCheckpoint emptied = loaded.value();
    emptied.radiance_cache.clear();
    emptied.guide.clear();
    resume.resume = &emptied;
    auto relearned = pipeline::bake(scene, s, *ctx_, resume);
    ASSERT_TRUE(relearned) << relearned.status().to_string();
    EXPECT_NE(0, std::memcmp(f.data(), relearned.value().irradiance.data(), f.size() * 4));
  }
}

// Adaptive sampling: the allocation depends only on the texels' state and
// the path count, so a bake resumed past the warm-up continues exactly.
// A point light over a plane gives texels different errors (uneven
// allocation, checked).
TEST_F(BakeControlTest, AdaptiveResumeFromCheckpointIsBitIdentical) {
  scene::Scene scene = testing::open_plane();
  scene::Light light;
  light.type = scene::LightType::kPoint;
  light.intensity = 3.0f;
  light.position = {0.1f, 0.75f, -0.2f};
  scene.lights.push_back(light);
  pipeline::BakeSettings s = settings();
  s.adaptive = true;
  s.adaptive_min_samples = 8;
  s.max_bounces = 0;
  auto full = pipeline::bake(scene, s, *ctx_);
  ASSERT_TRUE(full) << full.status().to_string();
  const pipeline::BakeResult& f = full.value();
  EXPECT_EQ(f.paths, uint64_t{64} * f.covered_texels);
  float lo = INFINITY, hi = 0;
  for (size_t t = 0; t < f.samples.size(); ++t) {
    if (f.irradiance[t * 4 + 3] < 1.0f) continue;
    lo = std::min(lo, f.samples[t]);
    hi = std::max(hi, f.samples[t]);
  }
  EXPECT_GE(lo, 8.0f);
  EXPECT_GT(hi, 1.5f * lo) << "the allocation should be uneven here";

  std::vector<pipeline::BakeCheckpoint> checkpoints;
  pipeline::BakeHooks hooks;
  hooks.fingerprint = "adaptive";
  hooks.checkpoint_interval_s = 1e-9;  // after every iteration
  hooks.on_checkpoint = [&](const pipeline::BakeCheckpoint& c) { checkpoints.push_back(c); };
  auto again = pipeline::bake(scene, s, *ctx_, hooks);
  ASSERT_TRUE(again);
  EXPECT_EQ(
      0, std::memcmp(f.irradiance.data(), again.value().irradiance.data(), f.irradiance.size() * 4))
      << "same seed and settings: same bits";
  // A checkpoint past the warm-up (adaptive iterations before and after).
  const pipeline::BakeCheckpoint* pick = nullptr;
  for (const auto& c : checkpoints)
    if (!pick && c.paths_done > uint64_t{16} * f.covered_texels &&
        c.paths_done < uint64_t{48} * f.covered_texels)
      pick = &c;
  ASSERT_NE(pick, nullptr) << checkpoints.size() << " checkpoints";
  pipeline::BakeHooks resume;
  resume.fingerprint = "adaptive";
  resume.resume = pick;
  auto resumed = pipeline::bake(scene, s, *ctx_, resume);
  ASSERT_TRUE(resumed) << resumed.status().to_string();
  EXPECT_EQ(resumed.value().paths, f.paths);
  EXPECT_EQ(0, std::memcmp(f.irradiance.data(), resumed.value().irradiance.data(),
                           f.irradiance.size() * 4))
      << "a resumed adaptive bake must produce the same bits as an uninterrupted one";
  EXPECT_EQ(0, std::memcmp(f.samples.data(), resumed.value().samples.data(), f.samples.size() * 4));
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

namespace luxel {
namespace {

// Benchmark mode: RMSE / relMSE against a reference lightmap.
// The bake's error estimate is the coverage-weighted mean of the covered
// texels' relative standard errors (kernels/bake/stats.h), recomputed here
// from the result's own images: coverage in the irradiance's alpha, the error
// in rel_error. With adaptive sampling the chart borders' partly covered
// texels take fewer paths, so the unweighted mean (the estimate before
// coverage counted) differs, and the check tells the two apart.
TEST_F(BakeControlTest, ErrorEstimateIsTheCoverageWeightedMean) {
  const scene::Scene scene = testing::furnace_box(0.5f, 0.25f);
  auto r = pipeline::bake(scene, settings(), *ctx_);
  ASSERT_TRUE(r) << r.status().to_string();
  const pipeline::BakeResult& b = r.value();
  double weighted = 0, coverage = 0, plain = 0;
  size_t covered = 0, partial = 0;
  for (size_t t = 0; t < size_t(b.width) * size_t(b.height); ++t) {
    const double a = b.irradiance[t * 4 + 3];
    if (!(a > 0)) continue;
    const double e = b.samples[t] < 2 ? 1.0 : std::min(1.0, double(b.rel_error[t]));
    weighted += a * e;
    coverage += a;
    plain += e;
    ++covered;
    if (a < 1) ++partial;
  }
  ASSERT_GT(partial, covered / 10) << "the atlas needs chart borders";
  const double expected = weighted / coverage, unweighted = plain / double(covered);
  std::printf("  error %.6f, coverage-weighted %.6f, unweighted %.6f (%zu of %zu partial)\n",
              b.error, expected, unweighted, partial, covered);
  EXPECT_NEAR(b.error, expected, 1e-4 * expected);
  EXPECT_GT(std::abs(unweighted - expected), 1e-2 * expected);
}

TEST_F(BakeControlTest, ReferenceErrorIsExactAndTracksTheEstimate) {
  // A plane under a uniform sky of radiance 1 (E = pi), given as an image:
  // the image sky is importance-sampled by its own distribution, not by the
  // cosine, so the estimate has variance (a constant sky is cosine-sampled
  // and converges with none, see closed_form_test).
  const scene::Scene scene = testing::open_plane();
  output::Image white;
  white.width = 16;
  white.height = 8;
  white.channels = 3;
  white.pixels.assign(white.texel_count() * 3, 1.0f);
  const std::string sky_path = ::testing::TempDir() + "/luxel_white_sky.exr";
  ASSERT_TRUE(output::write_exr(sky_path, white, {"R", "G", "B"}).is_ok());
  pipeline::BakeSettings st = settings();
  st.max_bounces = 0;
  st.samples_per_texel = 64;
  st.lights.sky.kind = pipeline::SkySettings::Kind::kEquirect;
  st.lights.sky.equirect_path = sky_path;
  st.lights.sky.color = {1, 1, 1};
  auto a = pipeline::bake(scene, st, *ctx_);
  ASSERT_TRUE(a) << a.status().to_string();
  EXPECT_LT(a.value().rmse, 0) << "no reference, no RMSE";

  // The bake's own result as reference: same seed, same bits, zero error.
  pipeline::BakeSettings same = st;
  same.reference = std::make_shared<const std::vector<float>>(a.value().irradiance);
  auto b = pipeline::bake(scene, same, *ctx_);
  ASSERT_TRUE(b) << b.status().to_string();
  EXPECT_EQ(b.value().rmse, 0.0);
  EXPECT_EQ(b.value().rel_mse, 0.0);

  // The exact answer (pi L) as reference: E[RMSE^2] is the mean variance of
  // the texel means, which the engine's own estimate gives as
  // (rel_error * mean)^2 for independent samples: with --random-sequence
  // their ratio must be near 1 (about 250 texels). With the Sobol sequence
  // the true error is smaller than the i.i.d. estimate (stratification), so
  // the estimate is conservative there.
  std::vector<float> exact(a.value().irradiance.size(), float(M_PI));
  for (size_t t = 0; t * 4 < exact.size(); ++t) exact[t * 4 + 3] = 1.0f;
  pipeline::BakeSettings vs_exact = st;
  vs_exact.seed = 5;
  vs_exact.reference = std::make_shared<const std::vector<float>>(exact);
  auto rmse_over_predicted = [&](const pipeline::BakeResult& r) {
    double predicted = 0;
    size_t n = 0;
    for (size_t t = 0; t < size_t(r.width) * r.height; ++t) {
      if (r.samples[t] < 2) continue;
      const double se = r.rel_error[t] * r.irradiance[t * 4];
      predicted += se * se;
      ++n;
    }
    predicted = std::sqrt(predicted / double(n));
    std::printf("  RMSE %.5f, predicted from the estimate %.5f, relMSE %.3g\n", r.rmse, predicted,
                r.rel_mse);
    return r.rmse / predicted;
  };
  auto c = pipeline::bake(scene, vs_exact, *ctx_);
  ASSERT_TRUE(c) << c.status().to_string();
  const auto& r = c.value();
  EXPECT_LT(rmse_over_predicted(r), 1.0) << "Sobol: the i.i.d. estimate must be conservative";
  pipeline::BakeSettings random = vs_exact;
  random.random_sequence = true;
  auto c_random = pipeline::bake(scene, random, *ctx_);
  ASSERT_TRUE(c_random) << c_random.status().to_string();
  const double ratio = rmse_over_predicted(c_random.value());
  EXPECT_GT(ratio, 0.8);
  EXPECT_LT(ratio, 1.25);
  ASSERT_FALSE(r.series.empty());
  for (const auto& e : r.series) EXPECT_TRUE(std::isfinite(e.rmse) && e.rmse >= 0);

  // Stopping on the true error; target metrics need a reference.
  pipeline::BakeSettings stop = vs_exact;
  stop.samples_per_texel = 0;
  stop.time_budget_s = 60;
  stop.target_metric = pipeline::ErrorMetric::kRmse;
  stop.target_error = r.rmse * 1.5;
  auto d = pipeline::bake(scene, stop, *ctx_);
  ASSERT_TRUE(d) << d.status().to_string();
  EXPECT_EQ(d.value().termination, pipeline::Termination::kError);
  EXPECT_LE(d.value().rmse, stop.target_error);
  stop.reference.reset();
  auto e = pipeline::bake(scene, stop, *ctx_);
  ASSERT_FALSE(e);
  EXPECT_NE(e.status().message().find("settings.target_metric"), std::string::npos)
      << e.status().to_string();
  // A reference of the wrong size names the setting.
  pipeline::BakeSettings wrong = st;
  wrong.reference = std::make_shared<const std::vector<float>>(std::vector<float>(12, 1.0f));
  auto f = pipeline::bake(scene, wrong, *ctx_);
  ASSERT_FALSE(f);
  EXPECT_NE(f.status().message().find("settings.reference"), std::string::npos)
      << f.status().to_string();
}

}  // namespace
}  // namespace luxel
