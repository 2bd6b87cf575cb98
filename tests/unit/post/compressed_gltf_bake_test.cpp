// Compressed glTF geometry (scene/gltf_decompress.h) through a whole bake
// and the write-back of lightmap UVs (post/lightmapped_gltf.h), on files of
// independent writers:
//  - Blender 5.0.1 exports one scene plain and with
//    KHR_draco_mesh_compression (tests/unit/scene/blender_compressed_export.py);
//    with the file's lightmap UVs both bake to the same lightmap within
//    Monte Carlo noise (same seeds; the geometry differs by Draco's
//    quantisation, so not bit for bit);
//  - gltfpack 1.2 packs scenes/cornell_box.gltf with and without
//    EXT_meshopt_compression (-cc); the compressed file bakes to the same
//    lightmap as the uncompressed pack.
// The written <scene>_lightmapped.glb of a compressed scene is plain glTF
// (neither extension) and bakes again to the same bits with its written
// UVs. Each case skips when its tool is not installed
// (tests/support/install-test-tools.sh).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "../scene/gltf_builder.h"
#include "bake/bake.h"
#include "post/bake_outputs.h"
#include "scene/gltf_import.h"
#include "support/device_context.h"

namespace luxel {
namespace {

using test::glb_json;
using test::read_all;

using nlohmann::json;

pipeline::BakeSettings settings(pipeline::UvMode mode) {
  pipeline::BakeSettings s;
  s.atlas.resolution = 64;
  s.samples_per_texel = 64;
  s.max_bounces = 2;
  s.paths_per_iteration = 1u << 15;
  s.lights.sky.kind = pipeline::SkySettings::Kind::kConstant;
  s.uv = mode;
  return s;
}

// Every texel finite and non-negative.
void expect_valid(const pipeline::BakeResult& r) {
  ASSERT_GT(r.covered_texels, 0u);
  for (size_t i = 0; i < r.irradiance.size(); ++i) {
    ASSERT_TRUE(std::isfinite(r.irradiance[i])) << i;
    ASSERT_GE(r.irradiance[i], 0.0f) << i;
  }
}

struct Agreement {
  size_t texels = 0, outliers = 0;
  double mean_ratio = 0;
  bool same() const { return outliers <= 3 * texels / 100 && std::fabs(mean_ratio - 1) < 0.01; }
};

// Two bakes of the same layout compared texel by texel over the texels
// fully covered in both: channel values that differ by more than 5
// standard errors of the difference (each texel's relative standard error
// from its bake), and the ratio of the means. `scale` multiplies b (an
// injected error).
Agreement compare(const pipeline::BakeResult& a, const pipeline::BakeResult& b, double scale = 1) {
  Agreement r;
  size_t& texels = r.texels;
  size_t& outliers = r.outliers;
  double sum_a = 0, sum_b = 0, worst_z = 0;
  for (size_t t = 0; t < static_cast<size_t>(a.width) * static_cast<size_t>(a.height); ++t) {
    if (a.irradiance[4 * t + 3] < 1.0f || b.irradiance[4 * t + 3] < 1.0f) continue;
    ++texels;
    for (size_t c = 0; c < 3; ++c) {
      const double x = a.irradiance[4 * t + c], y = scale * b.irradiance[4 * t + c];
      sum_a += x;
      sum_b += y;
      const double sx = a.rel_error[t] * x, sy = b.rel_error[t] * y;
      const double z = std::fabs(x - y) / std::sqrt(sx * sx + sy * sy + 1e-12);
      worst_z = std::max(worst_z, z);
      if (z > 5.0) ++outliers;
    }
  }
  r.mean_ratio = sum_b / sum_a;
  std::printf(
      "%zu texels compared: mean %.5g vs %.5g, %zu channel values over 5 sigma, largest "
      "z %.2f\n",
      texels, sum_a / (3.0 * static_cast<double>(texels)),
      sum_b / (3.0 * static_cast<double>(texels)), outliers, worst_z);
  return r;
}

// The bakes agree: at most 3 % of the channel values over 5 sigma, means
// within 1 %; and the comparison sees a 3 % error injected into b.
void expect_same_lightmap(const pipeline::BakeResult& a, const pipeline::BakeResult& b) {
  ASSERT_EQ(a.width, b.width);
  ASSERT_EQ(a.height, b.height);
  const Agreement same = compare(a, b);
  ASSERT_GT(same.texels, 100u);
  EXPECT_TRUE(same.same()) << same.outliers << " of " << 3 * same.texels
                           << " channel values over 5 sigma, mean ratio " << same.mean_ratio;
  EXPECT_FALSE(compare(a, b, 1.03).same()) << "an injected 3 % error must be seen";
}

class CompressedGltfBakeTest : public testing::DeviceTest<> {
 protected:
  static void SetUpTestSuite() {
    ASSERT_NO_FATAL_FAILURE(DeviceTest::SetUpTestSuite());
    dir_ = new test::TempDir;
    const char* python = std::getenv("LUXEL_BPY_PYTHON");
    const char* script = std::getenv("LUXEL_BLENDER_COMPRESSED_SCRIPT");
    if (python && *python && script) {
      const std::string cmd = std::string("'") + python + "' '" + script + "' -- '" + dir_->path() +
                              "' > /dev/null 2>&1";
      blender_ok_ = std::system(cmd.c_str()) == 0;
    }
    const char* gltfpack = std::getenv("LUXEL_GLTFPACK");
    if (gltfpack && *gltfpack) {
      const std::string in = std::string(LUXEL_SCENES_DIR) + "/cornell_box.gltf";
      gltfpack_ok_ = true;
      for (const auto& [name, flags] :
           {std::pair<const char*, const char*>{"packed.glb", ""}, {"meshopt.glb", "-cc"}}) {
        const std::string cmd = std::string("'") + gltfpack + "' -i '" + in + "' -o '" +
                                dir_->path() + "/" + name + "' " + flags + " > /dev/null 2>&1";
        gltfpack_ok_ = gltfpack_ok_ && std::system(cmd.c_str()) == 0;
      }
    }
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
    DeviceTest::TearDownTestSuite();
  }
  void need_blender() {
    const char* python = std::getenv("LUXEL_BPY_PYTHON");
    if (!python || !*python) GTEST_SKIP() << "LUXEL_BPY_PYTHON is not set";
    ASSERT_TRUE(blender_ok_) << "blender_compressed_export.py failed";
  }
  void need_gltfpack() {
    const char* gltfpack = std::getenv("LUXEL_GLTFPACK");
    if (!gltfpack || !*gltfpack) GTEST_SKIP() << "LUXEL_GLTFPACK is not set";
    ASSERT_TRUE(gltfpack_ok_) << "gltfpack failed";
  }
  static std::string path(const char* name) { return dir_->path() + "/" + name; }

  // Bakes `file` with generated UVs, writes it back, checks the written
  // file uses no compression extension, re-imports it with lightmap UVs and
  // bakes it again with them: the same bits.
  void write_back_round_trip(const std::string& file, const char* extension) {
    auto scene = scene::import_gltf_file(file);
    ASSERT_TRUE(scene) << scene.status().to_string();
    const auto s = settings(pipeline::UvMode::kGenerate);
    auto first = pipeline::bake(scene.value(), s, *ctx_);
    ASSERT_TRUE(first) << first.status().to_string();
    ASSERT_NO_FATAL_FAILURE(expect_valid(first.value()));
    auto written = pipeline::write_bake_outputs(dir_->path() + "/out", scene.value(), s,
                                                first.value(), "", file);
    ASSERT_TRUE(written) << written.status().to_string();
    ASSERT_FALSE(written.value().lightmapped_glb.empty());
    const std::string out = read_all(written.value().lightmapped_glb);
    const json j = glb_json(out);
    EXPECT_EQ(j.dump().find(extension), std::string::npos) << j.dump();
    auto again = scene::import_gltf_file(written.value().lightmapped_glb);
    ASSERT_TRUE(again) << again.status().to_string();
    for (const auto& m : again.value().meshes) EXPECT_TRUE(m.has_lightmap_uvs) << m.name;
    auto second = pipeline::bake(again.value(), settings(pipeline::UvMode::kExisting), *ctx_);
    ASSERT_TRUE(second) << second.status().to_string();
    ASSERT_EQ(second.value().irradiance.size(), first.value().irradiance.size());
    EXPECT_EQ(0, std::memcmp(second.value().irradiance.data(), first.value().irradiance.data(),
                             first.value().irradiance.size() * sizeof(float)))
        << "the written-back scene must bake to the same bits";
  }

  static inline test::TempDir* dir_ = nullptr;
  static inline bool blender_ok_ = false, gltfpack_ok_ = false;
};

TEST_F(CompressedGltfBakeTest, DracoSceneBakesLikeThePlainExport) {
  need_blender();
  if (IsSkipped() || HasFatalFailure()) return;
  auto plain = scene::import_gltf_file(path("plain.glb"));
  auto draco = scene::import_gltf_file(path("draco.glb"));
  ASSERT_TRUE(plain) << plain.status().to_string();
  ASSERT_TRUE(draco) << draco.status().to_string();
  // The file's lightmap UVs (Blender's unwrap, quantised to 12 bits in the
  // Draco file): the same atlas layout for both.
  const auto s = settings(pipeline::UvMode::kExisting);
  auto a = pipeline::bake(plain.value(), s, *ctx_);
  auto b = pipeline::bake(draco.value(), s, *ctx_);
  ASSERT_TRUE(a) << a.status().to_string();
  ASSERT_TRUE(b) << b.status().to_string();
  ASSERT_NO_FATAL_FAILURE(expect_valid(a.value()));
  ASSERT_NO_FATAL_FAILURE(expect_valid(b.value()));
  expect_same_lightmap(a.value(), b.value());
}

TEST_F(CompressedGltfBakeTest, MeshoptSceneBakesLikeTheUncompressedPack) {
  need_gltfpack();
  if (IsSkipped() || HasFatalFailure()) return;
  auto packed = scene::import_gltf_file(path("packed.glb"));
  auto meshopt = scene::import_gltf_file(path("meshopt.glb"));
  ASSERT_TRUE(packed) << packed.status().to_string();
  ASSERT_TRUE(meshopt) << meshopt.status().to_string();
  const auto s = settings(pipeline::UvMode::kAuto);
  auto a = pipeline::bake(packed.value(), s, *ctx_);
  auto b = pipeline::bake(meshopt.value(), s, *ctx_);
  ASSERT_TRUE(a) << a.status().to_string();
  ASSERT_TRUE(b) << b.status().to_string();
  ASSERT_NO_FATAL_FAILURE(expect_valid(b.value()));
  expect_same_lightmap(a.value(), b.value());
}

TEST_F(CompressedGltfBakeTest, DracoWriteBackIsPlainAndBakesTheSameBits) {
  need_blender();
  if (IsSkipped() || HasFatalFailure()) return;
  write_back_round_trip(path("draco.glb"), "KHR_draco_mesh_compression");
}

TEST_F(CompressedGltfBakeTest, MeshoptWriteBackIsPlainAndBakesTheSameBits) {
  need_gltfpack();
  if (IsSkipped() || HasFatalFailure()) return;
  write_back_round_trip(path("meshopt.glb"), "EXT_meshopt_compression");
}

}  // namespace
}  // namespace luxel
