// SceneCache and SceneStore's use of it: a scene imported to validate an
// upload is the scene the first bake gets, without a second import.
#include "service/scene_cache.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include "common/sha256.h"
#include "scene/gltf_builder.h"
#include "service/scene_store.h"
#include "service/scene_upload.h"

namespace luxel::service {
namespace {

// A fake importer: a scene with `triangles` triangles, named after the path;
// counts its calls.
struct FakeImporter {
  std::atomic<int> calls{0};
  size_t triangles = 1000;
  std::chrono::milliseconds delay{0};
  SceneCache::Importer fn() {
    return [this](const std::string& path) -> Result<scene::Scene> {
      ++calls;
      std::this_thread::sleep_for(delay);
      if (path == "broken") return invalid_argument("broken: not glTF");
      scene::Scene s;
      s.source_name = path;
      s.meshes.emplace_back();
      s.meshes.back().indices.assign(triangles * 3, 0);
      return s;
    };
  }
};

TEST(SceneCache, SecondUseDoesNotImport) {
  FakeImporter imp;
  SceneCache cache({}, imp.fn());
  auto a = cache.get_or_import("id1", "a.gltf");
  ASSERT_TRUE(a.is_ok());
  auto b = cache.get_or_import("id1", "a.gltf");
  ASSERT_TRUE(b.is_ok());
  EXPECT_EQ(a.value().get(), b.value().get()) << "the same shared scene";
  EXPECT_EQ(imp.calls, 1);
  EXPECT_EQ(cache.imports(), 1u);
}

TEST(SceneCache, PutThenGetDoesNotImport) {
  FakeImporter imp;
  SceneCache cache({}, imp.fn());
  auto s = cache.import("a.gltf");
  ASSERT_TRUE(s.is_ok());
  cache.put("id1", std::make_shared<const scene::Scene>(std::move(s.value())));
  auto again = cache.get_or_import("id1", "a.gltf");
  ASSERT_TRUE(again.is_ok());
  EXPECT_EQ(again.value()->source_name, "a.gltf");
  EXPECT_EQ(imp.calls, 1);
}

TEST(SceneCache, ErrorsAreReturnedAndNotCached) {
  FakeImporter imp;
  SceneCache cache({}, imp.fn());
  EXPECT_EQ(cache.get_or_import("bad", "broken").status().code(), StatusCode::kInvalidArgument);
  EXPECT_FALSE(cache.get_or_import("bad", "broken").is_ok());
  EXPECT_EQ(imp.calls, 2);
  EXPECT_EQ(cache.size(), 0u);
}

TEST(SceneCache, EvictsLeastRecentlyUsedByCount) {
  FakeImporter imp;
  SceneCache cache({/*max_scenes=*/2, /*max_bytes=*/uint64_t{1} << 30}, imp.fn());
  ASSERT_TRUE(cache.get_or_import("a", "a").is_ok());
  ASSERT_TRUE(cache.get_or_import("b", "b").is_ok());
  ASSERT_TRUE(cache.get_or_import("a", "a").is_ok());  // a is now the most recent
  ASSERT_TRUE(cache.get_or_import("c", "c").is_ok());  // evicts b
  EXPECT_EQ(imp.calls, 3);
  EXPECT_EQ(cache.size(), 2u);
  ASSERT_TRUE(cache.get_or_import("a", "a").is_ok());
  EXPECT_EQ(imp.calls, 3) << "a stayed";
  ASSERT_TRUE(cache.get_or_import("b", "b").is_ok());
  EXPECT_EQ(imp.calls, 4) << "b was evicted";
}

TEST(SceneCache, EvictsByBytesAndSkipsScenesOverTheBound) {
  FakeImporter imp;
  scene::Scene probe;
  probe.meshes.emplace_back();
  probe.meshes.back().indices.assign(imp.triangles * 3, 0);
  const uint64_t one = scene_bytes(probe);
  EXPECT_GE(one, imp.triangles * 3 * sizeof(uint32_t));
  SceneCache cache({/*max_scenes=*/10, /*max_bytes=*/one * 2 + one / 2}, imp.fn());
  for (const char* id : {"a", "b", "c"}) ASSERT_TRUE(cache.get_or_import(id, id).is_ok());
  EXPECT_EQ(cache.size(), 2u);
  EXPECT_LE(cache.bytes(), one * 2 + one / 2);
  imp.triangles = 10000;  // alone over the bound: served, not kept
  auto big = cache.get_or_import("big", "big");
  ASSERT_TRUE(big.is_ok());
  EXPECT_EQ(big.value()->meshes[0].indices.size(), 30000u);
  EXPECT_EQ(cache.size(), 2u);
}

TEST(SceneCache, EvictedSceneStaysAliveForItsHolder) {
  FakeImporter imp;
  SceneCache cache({/*max_scenes=*/1, uint64_t{1} << 30}, imp.fn());
  auto a = cache.get_or_import("a", "a.gltf");
  ASSERT_TRUE(a.is_ok());
  ASSERT_TRUE(cache.get_or_import("b", "b").is_ok());
  cache.erase("b");
  EXPECT_EQ(cache.size(), 0u);
  EXPECT_EQ(a.value()->source_name, "a.gltf");
}

TEST(SceneCache, ConcurrentMissesImportOnce) {
  FakeImporter imp;
  imp.delay = std::chrono::milliseconds(50);
  SceneCache cache({}, imp.fn());
  std::vector<std::thread> threads;
  std::atomic<int> ok{0};
  for (int i = 0; i < 8; ++i)
    threads.emplace_back([&] { ok += cache.get_or_import("id", "x.gltf").is_ok() ? 1 : 0; });
  for (auto& t : threads) t.join();
  EXPECT_EQ(ok, 8);
  EXPECT_EQ(imp.calls, 1);
}

// A real upload through SceneUpload into a SceneStore on disk.
class SceneStoreCache : public ::testing::Test {
 protected:
  void SetUp() override {
    test::GltfBuilder b;
    const int mesh = b.add_mesh("quad", {b.triangles(test::kQuadPositions, test::kQuadIndices)});
    b.add_node({{"mesh", mesh}, {"name", "n"}});
    gltf_ = b.gltf_embedded();
  }

  Result<v1::SceneInfo> upload(SceneStore& store) {
    v1::SceneUploadHeader h;
    h.set_name("quad.gltf");
    h.set_format(v1::SCENE_FORMAT_GLTF);
    h.set_total_size(gltf_.size());
    h.set_sha256(sha256_hex(gltf_));
    auto up = SceneUpload::begin(store, h, UploadLimits{});
    if (!up) return up.status();
    LUXEL_RETURN_IF_ERROR(up.value()->write(gltf_));
    return up.value()->finish();
  }

  test::TempDir dir_;
  std::string gltf_;
};

TEST_F(SceneStoreCache, BakeOfAJustUploadedSceneDoesNotImportAgain) {
  auto store = SceneStore::open(dir_.path());
  ASSERT_TRUE(store.is_ok()) << store.status().to_string();
  auto info = upload(*store.value());
  ASSERT_TRUE(info.is_ok()) << info.status().to_string();
  EXPECT_EQ(store.value()->scene_imports(), 1u) << "commit validates by importing";
  auto scene = store.value()->load_scene(info.value());
  ASSERT_TRUE(scene.is_ok()) << scene.status().to_string();
  EXPECT_EQ(store.value()->scene_imports(), 1u) << "the bake got the validated import";
  EXPECT_EQ(scene.value()->meshes.size(), 1u);
  // Named as an import of the stored file would be (manifests carry it).
  EXPECT_EQ(scene.value()->source_name, store.value()->main_file_path(info.value()));
  // Uploading the same bytes again is an already_stored hit: no import.
  auto again = upload(*store.value());
  ASSERT_TRUE(again.is_ok());
  EXPECT_TRUE(again->already_stored());
  EXPECT_EQ(store.value()->scene_imports(), 1u);
}

TEST_F(SceneStoreCache, AfterARestartTheSceneIsImportedOnDemandOnce) {
  v1::SceneInfo info;
  {
    auto store = SceneStore::open(dir_.path());
    ASSERT_TRUE(store.is_ok());
    auto committed = upload(*store.value());
    ASSERT_TRUE(committed.is_ok()) << committed.status().to_string();
    info = committed.value();
  }
  auto store = SceneStore::open(dir_.path());  // the daemon restarted
  ASSERT_TRUE(store.is_ok());
  auto stored = store.value()->get(info.scene_id());
  ASSERT_TRUE(stored.is_ok());
  EXPECT_EQ(store.value()->scene_imports(), 0u);
  auto first = store.value()->load_scene(stored.value());
  ASSERT_TRUE(first.is_ok()) << first.status().to_string();
  EXPECT_EQ(store.value()->scene_imports(), 1u);
  auto second = store.value()->load_scene(stored.value());
  ASSERT_TRUE(second.is_ok());
  EXPECT_EQ(store.value()->scene_imports(), 1u);
  EXPECT_EQ(first.value()->source_name, second.value()->source_name);
  // A removed scene leaves the cache with the store.
  ASSERT_TRUE(store.value()->remove(info.scene_id()).is_ok());
  EXPECT_FALSE(store.value()->load_scene(stored.value()).is_ok());
}

}  // namespace
}  // namespace luxel::service
