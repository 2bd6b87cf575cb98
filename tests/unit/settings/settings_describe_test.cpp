// BakeSettings::describe() is the settings fingerprint: checkpoints and
// shard merges compare it (settings/fingerprint.cpp hashes it), so its text
// must not drift when the schema it is built from changes. The expectations
// are written out by hand, key by key, for the defaults and for two bakes
// that move every setting the fingerprint covers.
#include <gtest/gtest.h>

#include <map>
#include <memory>
#include <string>

#include "settings/bake_settings.h"
#include "settings/fingerprint.h"
#include "settings/settings_schema.h"

namespace luxel::pipeline {
namespace {

using Described = std::map<std::string, std::string>;

TEST(SettingsDescribe, Defaults) {
  const Described expected = {
      {"adaptive", "on,min=8"},
      {"clamp_luminance", "0"},
      {"compaction", "on"},
      {"dilation_texels", "2"},
      {"filter", "box"},
      {"intersector", "auto"},
      {"max_bounces", "4"},
      {"max_resolution", "1024"},
      {"paths_per_iteration", "auto"},
      {"radiance_cache", "on"},
      {"rr_depth", "3"},
      {"samples_per_texel", "256"},
      {"seam_stitch", "on"},
      {"seed", "1"},
      {"sequence", "sobol"},
      {"sky", "none"},
      {"sort_directions", "off"},
      {"target_error", "0"},
      {"texel_density", "40"},
      {"time_budget_s", "0"},
      {"uv", "auto"},
  };
  EXPECT_EQ(default_settings().describe(), expected);
  // A fixed size: the resolution, and neither the density nor the page
  // size, which it overrides.
  BakeSettings fixed = default_settings();
  fixed.atlas.resolution = 256;
  fixed.atlas.texel_density = 0;
  Described with_resolution = expected;
  with_resolution.erase("texel_density");
  with_resolution.erase("max_resolution");
  with_resolution["resolution"] = "256";
  EXPECT_EQ(fixed.describe(), with_resolution);
}

// Every setting away from its default; the daemon's job settings, the
// progress interval, the sun's colour and the directional lights' radius are
// not part of the fingerprint and must not appear.
TEST(SettingsDescribe, EverySettingMoved) {
  BakeSettings s = default_settings();
  s.atlas.resolution = 0;
  s.atlas.texel_density = 12.5f;
  s.atlas.max_resolution = 2048;
  s.samples_per_texel = 1000;
  s.time_budget_s = 1e6;  // %g: "1e+06"
  s.target_error = 0.01;
  s.target_metric = ErrorMetric::kRmse;
  s.reference = std::make_shared<const std::vector<float>>(4, 0.f);
  s.reference_name = "ref.exr";
  s.max_bounces = 8;
  s.rr_depth = 5;
  s.paths_per_iteration = 65536;
  s.device_memory_budget_mib = 512.5;
  s.seed = 7;
  s.filter = Filter::kGaussian;
  s.direct = DirectLight::kSampled;
  s.intersector = accel::IntersectorKind::kEmbree;
  s.uv = UvMode::kGenerate;
  s.clamp_luminance = 10;
  s.adaptive_min_samples = 16;
  s.compaction = false;
  s.sort_directions = true;
  s.random_sequence = true;
  s.dilation_texels = 0;
  s.denoise = Denoise::kAtrous;
  s.seam_stitch = false;
  s.radiance_cache = false;
  s.guiding = true;
  s.encodings.names = {"sh2", "sg9"};
  s.encodings.sg_sharpness = 4;
  s.encodings.solver = EncodingSolver::kProgressiveNonNegative;
  s.encodings.acceleration = 2.5f;
  s.lights.sky.kind = SkySettings::Kind::kConstant;
  s.lights.sky.color = {0.5f, 0.25f, 1};
  s.lights.sky.intensity = 2;
  s.lights.sun.enabled = true;
  s.lights.sun.direction = {1, -2, 0.5f};
  s.lights.sun.color = {1, 0, 0};
  s.lights.sun.illuminance = 3;
  s.lights.sun.angular_radius_degrees = 0.5f;
  s.lights.directional_angular_radius_degrees = 1;
  s.probes = "grid:0.5";
  s.probe_sh_order = 1;
  s.probe_window = "lanczos";
  s.probe_positions = "[[0,0,0],[1,2,3]]";
  s.lightmap = false;
  s.node_placements = {
      {.node = 3, .element = -1, .scale_offset = {0.5f, 0.5f, 0.25f, 0}, .page = 1},
      {.node = 4, .element = 2, .scale_offset = {1, 1, 0, 0}, .page = 0}};
  s.progress_interval_s = 0.5;
  s.job.priority = 5;
  s.job.snapshot_interval_s = 2;
  s.job.snapshot_format = SnapshotFormat::kExr;
  s.job.snapshot_max_side = 64;
  s.job.reference_bake_id = "b1";
  s.job.denoise_snapshots = true;
  s.job.shards = 3;
  s.job.shards_auto = true;

  const Described expected = {
      {"acceleration", "2.5"},
      {"adaptive", "on,min=16"},
      {"clamp_luminance", "10"},
      {"compaction", "off"},
      {"denoise", "atrous"},
      {"guiding", "on"},
      {"device_memory_budget_mib", "512.5"},
      {"dilation_texels", "0"},
      {"direct", "sampled"},
      {"encodings", "irradiance,sh2,sg9"},
      {"filter", "gaussian"},
      {"intersector", "embree"},
      {"lightmap", "off"},
      {"max_bounces", "8"},
      {"paths_per_iteration", "65536"},
      {"placements", "3:0.5,0.5,0.25,0@1 4/2:1,1,0,0@0"},
      // FNV-1a 64 of the JSON text from the offset basis describe() has
      // always used, 1469598103934665603 (not the standard one).
      {"probe_positions_fnv1a", "b916ceff4ddc933b"},
      {"probe_sh_order", "1"},
      {"probe_window", "lanczos"},
      {"probes", "grid:0.5"},
      {"radiance_cache", "off"},
      {"reference", "ref.exr"},
      {"max_resolution", "2048"},
      {"rr_depth", "5"},
      {"samples_per_texel", "1000"},
      {"seam_stitch", "off"},
      {"seed", "7"},
      {"sequence", "random"},
      {"sg_sharpness", "4"},
      {"sky", "constant 0.5,0.25,1 x 2"},
      {"solver", "progressive-nn"},
      {"sort_directions", "on"},
      {"sun", "dir 1,-2,0.5 E 3 radius 0.5 deg"},
      {"target_error", "0.01"},
      {"target_metric", "rmse"},
      {"texel_density", "12.5"},
      {"time_budget_s", "1e+06"},
      {"uv", "generate"},
  };
  EXPECT_EQ(s.describe(), expected);
}

// A shard of an equirect-sky bake with an unnamed reference and node probes.
TEST(SettingsDescribe, ShardEquirectSkyAndNodeProbes) {
  BakeSettings s = default_settings();
  s.shard_index = 1;
  s.shard_count = 4;
  s.adaptive = false;
  s.reference = std::make_shared<const std::vector<float>>(4, 0.f);
  s.lights.sky.kind = SkySettings::Kind::kEquirect;
  s.lights.sky.equirect_path = "sky.exr";
  s.lights.sky.intensity = 1.5f;
  s.lights.sky.rotation_degrees = 90;
  s.probes = "nodes";
  s.direct = DirectLight::kAnalytic;
  s.uv = UvMode::kExisting;
  s.intersector = accel::IntersectorKind::kOpenCl;
  s.target_metric = ErrorMetric::kRelMse;

  Described expected = default_settings().describe();
  expected["shard"] = "1/4";
  expected["adaptive"] = "off";
  expected["reference"] = "given";
  expected["sky"] = "equirect sky.exr x 1.5 rot 90";
  expected["probes"] = "nodes";
  expected["probe_sh_order"] = "2";
  expected["probe_window"] = "hanning";
  expected["direct"] = "analytic";
  expected["uv"] = "existing";
  expected["intersector"] = "opencl";
  expected["target_metric"] = "relmse";
  EXPECT_EQ(s.describe(), expected);
}

// The fingerprint of default settings is pinned: a change here orphans every
// checkpoint on disk, so it must be deliberate. (Changed when the default
// size became texel_density 40 on pages of max_resolution 1024 instead of
// resolution 512: a default bake is another lightmap; when seam_stitch
// became on by default; and when the radiance cache did.)
TEST(SettingsDescribe, DefaultFingerprintIsPinned) {
  EXPECT_EQ(bake_fingerprint("scene", default_settings()), "0b91ed83cb83966d621255f8fa64a67b");
}

}  // namespace
}  // namespace luxel::pipeline
