// Golden hashes of small bakes: the same scene, settings, seed and device
// must give the same bits (DESIGN.md "Deterministic"), across refactorings
// of the bake core too. Each case bakes a bundled scene with a fixed set of
// features switched on and hashes every output the bake returns
// (irradiance, samples, relative error, the coefficients of every
// directional encoding, path and drop counts).
//
// Recorded hashes live in golden_bake_hashes.tsv, one line per
// (device, case). Float bits depend on the OpenCL compiler and the CPU's
// vector width (and the host build, for what the host computes), so a hash
// is only compared on the device and build flavour it was recorded on. On a device without recorded
// hashes every case is baked twice and the two must agree bit for bit (determinism still checked),
// and the test prints the lines to add. LUXEL_GOLDEN_RECORD=FILE appends this device's lines to
// FILE.
//
// A change that is meant to change the bits (a new estimator, a fixed bias)
// re-records the case's lines in the same commit where it can, deletes the
// case's lines for every device it cannot re-record, and says so in the
// message. A recorded device without a line for a case checks that case's
// determinism only (two bakes, identical bits) until someone records it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "bake/bake.h"
#include "common/hash.h"
#include "device/context.h"
#include "output/exr.h"
#include "scene/gltf_import.h"

namespace luxel {
namespace {

std::string scene_path(const char* name) {
  return std::string(LUXEL_SCENES_DIR) + "/" + name;
}

// Hash of everything a bake returns that depends on the traced bits.
std::string result_hash(const pipeline::BakeResult& r) {
  Hasher h;
  auto add_floats = [&](const std::vector<float>& v) {
    h.add_u64(v.size());
    h.add(v.data(), v.size() * sizeof(float));
  };
  h.add_u64(static_cast<uint64_t>(r.width));
  h.add_u64(static_cast<uint64_t>(r.height));
  add_floats(r.irradiance);
  add_floats(r.samples);
  add_floats(r.rel_error);
  h.add_u64(r.paths);
  h.add_u64(r.nonfinite_dropped);
  for (const auto& e : r.encodings) {
    h.add(e.name);
    add_floats(e.coefficients);
  }
  return h.hex();
}

struct GoldenCase {
  std::string name;
  std::string scene;  // file under scenes/
  std::function<void(pipeline::BakeSettings&)> configure;
  int resume_after_checkpoint = -1;  // >= 0: bake, keep checkpoint k, resume from it
};

pipeline::BakeSettings base_settings() {
  pipeline::BakeSettings s;
  s.atlas.resolution = 32;
  s.samples_per_texel = 8;
  s.max_bounces = 3;
  s.paths_per_iteration = 2048;  // several iterations per bake
  s.seed = 7;
  s.progress_interval_s = 1e9;
  // The cases below pin the OpenCL traversal (their hashes predate the
  // Embree backend); the *_embree cases repeat some on the Embree backend.
  s.intersector = accel::IntersectorKind::kOpenCl;
  return s;
}

// The foliage scene at 64^2, 2 bounces, under a constant sky and a sun (its
// own point, spot and directional lights stay on).
void foliage_sun_and_sky(pipeline::BakeSettings& s) {
  s.atlas.resolution = 64;
  s.max_bounces = 2;
  s.lights.sky.kind = pipeline::SkySettings::Kind::kConstant;
  s.lights.sky.color = {0.4f, 0.5f, 0.7f};
  s.lights.sun.enabled = true;
  s.lights.sun.direction = {0.3f, -1.0f, 0.2f};
  s.lights.sun.illuminance = 5.0f;
}

// A small equirect sky with structure in every direction.
std::string write_sky_image() {
  output::Image img;
  img.width = 16;
  img.height = 8;
  img.channels = 3;
  img.pixels.resize(img.texel_count() * 3);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      img.at(x, y, 0) = 0.2f + 0.1f * static_cast<float>(x % 4);
      img.at(x, y, 1) = 0.3f + 0.05f * static_cast<float>(y);
      img.at(x, y, 2) = (x == 3 && y == 2) ? 40.0f : 0.5f;
    }
  const std::string path = ::testing::TempDir() + "/luxel_golden_sky.exr";
  EXPECT_TRUE(output::write_exr(path, img, {"R", "G", "B"}).is_ok());
  return path;
}

std::vector<GoldenCase> golden_cases(const std::string& sky_path) {
  using S = pipeline::BakeSettings;
  return {
      {"cornell_default", "cornell_box.gltf", [](S&) {}},
      {"cornell_ablations", "cornell_box.gltf",
       [](S& s) {
         s.sort_directions = true;
         s.compaction = false;
         s.filter = pipeline::Filter::kGaussian;
         s.clamp_luminance = 2.0f;
         s.rr_depth = 1;
       }},
      {"cornell_sorted_compacted", "cornell_box.gltf",
       [](S& s) {
         s.sort_directions = true;
         s.random_sequence = true;
         s.max_bounces = 0;
       }},
      {"foliage_lights_sun_sky", "foliage_instanced.glb",
       [](S& s) {
         foliage_sun_and_sky(s);
         s.lights.directional_angular_radius_degrees = 0.5f;
       }},
      {"foliage_sky_image", "foliage_instanced.glb",
       [sky_path](S& s) {
         s.atlas.resolution = 48;
         s.max_bounces = 1;
         s.lights.sky.kind = pipeline::SkySettings::Kind::kEquirect;
         s.lights.sky.equirect_path = sky_path;
         s.lights.sky.rotation_degrees = 30.0f;
         s.lights.sky.intensity = 0.5f;
       }},
      {"cornell_encodings_auto", "cornell_box.gltf",
       [](S& s) {
         s.encodings.names = {"sh1",  "sh2",           "sg6",           "sg9-hemi",
                              "sg12", "ambient-dice9", "ambient-dice12"};
       }},
      {"cornell_encodings_projection", "cornell_box.gltf",
       [](S& s) {
         s.encodings.names = {"sh2", "sg9", "ambient-dice9"};
         s.encodings.solver = pipeline::EncodingSolver::kProjection;
       }},
      {"cornell_encodings_progressive", "cornell_box.gltf",
       [](S& s) {
         s.encodings.names = {"sh2", "sg12-hemi"};
         s.encodings.solver = pipeline::EncodingSolver::kProgressive;
         s.encodings.acceleration = 2.0f;
         s.encodings.sg_sharpness = 5.0f;
       }},
      {"foliage_encodings_nn", "foliage_instanced.glb",
       [](S& s) {
         s.encodings.names = {"ambient-dice12", "sg6-hemi"};
         s.encodings.solver = pipeline::EncodingSolver::kProgressiveNonNegative;
         s.max_bounces = 1;
       }},
      {"cornell_resumed", "cornell_box.gltf",
       [](S& s) {
         s.encodings.names = {"sh2", "ambient-dice9"};
       },
       1},
      // The Embree backend: its own bits, as deterministic (alpha masks,
      // punctual lights, direction sorting, encodings, resume).
      {"cornell_default_embree", "cornell_box.gltf",
       [](S& s) { s.intersector = accel::IntersectorKind::kEmbree; }},
      {"foliage_lights_sun_sky_embree", "foliage_instanced.glb",
       [](S& s) {
         s.intersector = accel::IntersectorKind::kEmbree;
         foliage_sun_and_sky(s);
         s.sort_directions = true;
       }},
      {"cornell_resumed_embree", "cornell_box.gltf",
       [](S& s) {
         s.intersector = accel::IntersectorKind::kEmbree;
         s.encodings.names = {"sh2", "sg9-hemi"};
       },
       1},
  };
}

Result<pipeline::BakeResult> run_case(const GoldenCase& c, device::Context& ctx) {
  auto scene = scene::import_gltf_file(scene_path(c.scene.c_str()));
  if (!scene) return scene.status();
  pipeline::BakeSettings s = base_settings();
  c.configure(s);
  if (c.resume_after_checkpoint < 0) return pipeline::bake(scene.value(), s, ctx);
  std::vector<pipeline::BakeCheckpoint> checkpoints;
  pipeline::BakeHooks hooks;
  hooks.fingerprint = c.name;
  hooks.checkpoint_interval_s = 1e-9;  // after every iteration
  hooks.on_checkpoint = [&](const pipeline::BakeCheckpoint& k) { checkpoints.push_back(k); };
  auto full = pipeline::bake(scene.value(), s, ctx, hooks);
  if (!full) return full.status();
  if (checkpoints.size() <= static_cast<size_t>(c.resume_after_checkpoint))
    return internal_error("golden case " + c.name + ": too few checkpoints");
  pipeline::BakeHooks resume;
  resume.fingerprint = c.name;
  resume.resume = &checkpoints[static_cast<size_t>(c.resume_after_checkpoint)];
  return pipeline::bake(scene.value(), s, ctx, resume);
}

// device -> case -> hash
std::map<std::string, std::map<std::string, std::string>> read_golden(const std::string& path) {
  std::map<std::string, std::map<std::string, std::string>> out;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string device, name, hash;
    if (std::getline(fields, device, '\t') && std::getline(fields, name, '\t') &&
        std::getline(fields, hash, '\t'))
      out[device][name] = hash;
  }
  return out;
}

TEST(GoldenBake, SameSeedsGiveTheRecordedBits) {
  auto ctx = device::Context::create();
  ASSERT_TRUE(ctx) << ctx.status().to_string();
  // The compiler and vector width decide the float bits, not the memory
  // size or the number of cores: key by device, platform and driver.
  const auto& info = ctx.value()->info();
  // Sanitizer builds compile the host code differently (the sky
  // distribution's float sums came out other bits), so they are a device of
  // their own; without recorded hashes they check determinism only.
  const std::string device = info.device_name + " | " + info.platform_name + " " +
                             info.driver_version + " | " + LUXEL_GOLDEN_BUILD;
  const auto golden = read_golden(LUXEL_GOLDEN_FILE);
  const auto recorded = golden.find(device);
  const bool known_device = recorded != golden.end();
  const std::string sky = write_sky_image();

  std::ostringstream lines;
  for (const auto& c : golden_cases(sky)) {
    SCOPED_TRACE(c.name);
    auto r = run_case(c, *ctx.value());
    ASSERT_TRUE(r) << r.status().to_string();
    ASSERT_GT(r.value().paths, 0u);
    const std::string hash = result_hash(r.value());
    lines << device << '\t' << c.name << '\t' << hash << '\n';
    // A case whose lines were deleted for this device (its bits changed on
    // purpose and could not be re-recorded here) checks determinism only.
    const std::string* expected = nullptr;
    if (known_device) {
      const auto it = recorded->second.find(c.name);
      if (it != recorded->second.end()) expected = &it->second;
    }
    if (expected) {
      EXPECT_EQ(*expected, hash) << "case " << c.name << " changed its output bits";
    } else {
      auto again = run_case(c, *ctx.value());
      ASSERT_TRUE(again) << again.status().to_string();
      EXPECT_EQ(hash, result_hash(again.value()))
          << "two bakes of case " << c.name << " differ: the bake is not deterministic";
    }
  }
  if (const char* record = std::getenv("LUXEL_GOLDEN_RECORD")) {
    std::ofstream out(record, std::ios::app);
    out << lines.str();
  }
  if (!known_device)
    std::printf("No golden hashes recorded for this device; lines to add to %s:\n%s",
                LUXEL_GOLDEN_FILE, lines.str().c_str());
}

// The check must be able to fail: one changed seed changes the hash.
TEST(GoldenBake, HashSeesAOneSeedChange) {
  auto ctx = device::Context::create();
  ASSERT_TRUE(ctx) << ctx.status().to_string();
  auto scene = scene::import_gltf_file(scene_path("cornell_box.gltf"));
  ASSERT_TRUE(scene) << scene.status().to_string();
  pipeline::BakeSettings s = base_settings();
  auto a = pipeline::bake(scene.value(), s, *ctx.value());
  s.seed += 1;
  auto b = pipeline::bake(scene.value(), s, *ctx.value());
  ASSERT_TRUE(a && b);
  EXPECT_NE(result_hash(a.value()), result_hash(b.value()));
}

}  // namespace
}  // namespace luxel
