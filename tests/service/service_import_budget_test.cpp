// The daemon's import budget against the real luxeld: hostile uploads (a
// zero-filled accessor of 50 million vertices, all-zero PNGs of 16 million
// texels, several at once) are refused with RESOURCE_EXHAUSTED naming the
// accessor / image and the daemon's --import-memory-budget; the budget is
// shared and given back; --import-timeout ends a long import with
// DEADLINE_EXCEEDED. Nothing is stored for a refused upload.
#include <gtest/gtest.h>

#include <filesystem>
#include <thread>

#include "daemon_harness.h"

namespace luxel::test {
namespace {

namespace fs = std::filesystem;

bool staging_empty(const Daemon& d) {
  return fs::is_empty(d.data_dir() + "/staging");
}

void expect_message(const grpc::Status& st, std::initializer_list<const char*> needles) {
  for (const char* n : needles)
    EXPECT_NE(st.error_message().find(n), std::string::npos)
        << "'" << n << "' not in: " << st.error_message();
}

// A mesh whose POSITION accessor has no bufferView (all zeros) and `count`
// vertices: a few hundred bytes.
std::string zero_accessor_gltf(uint64_t count) {
  GltfBuilder b;
  b.doc["accessors"].push_back({{"componentType", kFloat},
                                {"count", count},
                                {"type", "VEC3"},
                                {"min", {0, 0, 0}},
                                {"max", {0, 0, 0}}});
  b.add_node({{"mesh", b.add_mesh("bomb", {{{"attributes", {{"POSITION", 0}}}}})}});
  return b.gltf_embedded();
}

// A quad whose base colour is an all-zero greyscale PNG of side x side
// texels; `tag` makes each file (and its scene id) different.
std::string zero_png_gltf(int side, int tag) {
  GltfBuilder b;
  const int mesh = b.add_mesh("quad", {b.triangles(kQuadPositions, kQuadIndices)});
  b.add_node({{"mesh", mesh}, {"name", "n" + std::to_string(tag)}});
  const std::string png =
      encode_png(side, side, 1, std::vector<uint8_t>(size_t(side) * size_t(side), 0));
  b.doc["images"] = json::array({{{"uri", "data:image/png;base64," + base64(png)}}});
  b.doc["textures"] = json::array({{{"source", 0}}});
  b.add_material({{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}});
  b.doc["meshes"][0]["primitives"][0]["material"] = 0;
  return b.gltf_embedded();
}

class ServiceImportBudget : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir();
    daemon_ = new Daemon(dir_->path() + "/data", {"--import-memory-budget", "256MiB"});
  }
  static void TearDownTestSuite() {
    EXPECT_EQ(daemon_->stop(SIGTERM), 0);
    delete daemon_;
    delete dir_;
  }
  static TempDir* dir_;
  static Daemon* daemon_;
};
TempDir* ServiceImportBudget::dir_ = nullptr;
Daemon* ServiceImportBudget::daemon_ = nullptr;

TEST_F(ServiceImportBudget, ZeroFilledAccessorIsRefusedNamingTheAccessorAndBudget) {
  v1::SceneInfo info;
  auto st = upload_scene(*daemon_, "bomb.gltf", v1::SCENE_FORMAT_GLTF,
                         zero_accessor_gltf(uint64_t{3} << 24), {}, &info);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << st.error_message();
  expect_message(st, {"bomb.gltf", "accessor 0 (POSITION)", "50331648 vertices",
                      "the daemon's import memory budget (--import-memory-budget)", "256.0 MiB"});
  EXPECT_TRUE(staging_empty(*daemon_));
}

TEST_F(ServiceImportBudget, PngBombIsRefusedNamingTheImage) {
  // 8192^2 texels: 64 MiB kept + 384 MiB while stb_image decodes.
  v1::SceneInfo info;
  auto st =
      upload_scene(*daemon_, "png.gltf", v1::SCENE_FORMAT_GLTF, zero_png_gltf(8192, 0), {}, &info);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << st.error_message();
  expect_message(st, {"png.gltf", "image 0 (8192 x 8192)",
                      "the daemon's import memory budget (--import-memory-budget)"});
  EXPECT_TRUE(staging_empty(*daemon_));
}

// Four uploads of 4096^2 texels at once (each reserves ~160 MiB of the 256
// MiB pool while it decodes, 64 MiB after, so each fits alone): each is stored, or refused for the
// shared budget while the others import; afterwards the budget is whole again, so every one of them
// uploads one after the other. (Which ones overlap is up to the scheduler;
// tests/unit/scene/import_budget_test.cpp refuses one deterministically.)
TEST_F(ServiceImportBudget, ConcurrentUploadsShareTheBudgetAndGiveItBack) {
  constexpr int kUploads = 4;
  std::vector<std::string> files;
  for (int i = 0; i < kUploads; ++i) files.push_back(zero_png_gltf(4096, 10 + i));
  std::vector<grpc::Status> results(kUploads);
  std::vector<std::thread> threads;
  for (int i = 0; i < kUploads; ++i) {
    threads.emplace_back([&, i] {
      v1::SceneInfo info;
      results[size_t(i)] = upload_scene(*daemon_, "c" + std::to_string(i) + ".gltf",
                                        v1::SCENE_FORMAT_GLTF, files[size_t(i)], {}, &info);
    });
  }
  for (auto& t : threads) t.join();
  for (const auto& st : results) {
    if (st.ok()) continue;
    EXPECT_EQ(st.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << st.error_message();
    expect_message(st, {"the daemon's import memory budget", "other imports"});
  }
  for (int i = 0; i < kUploads; ++i) {
    v1::SceneInfo info;
    auto st = upload_scene(*daemon_, "c" + std::to_string(i) + ".gltf", v1::SCENE_FORMAT_GLTF,
                           files[size_t(i)], {}, &info);
    EXPECT_TRUE(st.ok()) << st.error_message();
  }
  EXPECT_TRUE(staging_empty(*daemon_));
}

TEST(ServiceImportTimeout, LongImportIsDeadlineExceeded) {
  TempDir dir;
  Daemon d(dir.path() + "/data", {"--import-timeout", "0.001"});
  // 2 million zero vertices: ~130 MB of budget, some tens of milliseconds.
  v1::SceneInfo info;
  auto st =
      upload_scene(d, "slow.gltf", v1::SCENE_FORMAT_GLTF, zero_accessor_gltf(2000001), {}, &info);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::DEADLINE_EXCEEDED) << st.error_message();
  expect_message(st, {"slow.gltf", "time limit of 0.001 s", "--import-timeout"});
  EXPECT_TRUE(staging_empty(d));
  EXPECT_EQ(d.stop(SIGTERM), 0);
}

}  // namespace
}  // namespace luxel::test
