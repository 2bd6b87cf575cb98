// What an import may cost (scene/import_budget.h): the hostile files measured
// against luxeld (a zero-filled accessor of 50 million vertices, a million
// EXT_mesh_gpu_instancing instances, all-zero PNGs of 65 million texels) are
// refused before their memory is allocated, naming the accessor / extension /
// image and the bytes; imports sharing one pool; a file at exactly its peak
// reservation is accepted; the time limit.
#include <gtest/gtest.h>

#include <limits>

#include "gltf_builder.h"
#include "scene/gltf_import.h"

namespace luxel::scene {
namespace {

using test::GltfBuilder;
using test::json;
using test::kQuadIndices;
using test::kQuadPositions;

constexpr uint64_t kMiB = uint64_t{1} << 20;

Result<Scene> load(const std::string& bytes, const ImportOptions& options) {
  return import_gltf_memory(bytes, "", "test.gltf", options);
}

void expect_error(const Result<Scene>& r, StatusCode code,
                  std::initializer_list<const char*> needles) {
  ASSERT_FALSE(r.is_ok());
  EXPECT_EQ(r.status().code(), code) << r.status().to_string();
  for (const char* n : needles)
    EXPECT_NE(r.status().message().find(n), std::string::npos)
        << "'" << n << "' not in: " << r.status().message();
}

ImportOptions budget_of(uint64_t bytes) {
  ImportOptions o;
  o.max_import_bytes = bytes;
  return o;
}

GltfBuilder quad_scene() {
  GltfBuilder b;
  const int mesh = b.add_mesh("quad", {b.triangles(kQuadPositions, kQuadIndices)});
  b.add_node({{"mesh", mesh}, {"name", "n"}});
  return b;
}

// A POSITION accessor without a bufferView is all zeros (glTF 2.0 §3.6.2.3):
// 3 * 2^24 vertices in a few hundred bytes of JSON. Measured against luxeld
// before the budget: 13 s and +3.2 GB of RSS (~64 bytes per vertex).
TEST(ImportBudget, ZeroFilledAccessorIsRefusedBeforeAllocating) {
  GltfBuilder b;
  b.doc["accessors"].push_back({{"componentType", test::kFloat},
                                {"count", 3 << 24},
                                {"type", "VEC3"},
                                {"min", {0, 0, 0}},
                                {"max", {0, 0, 0}}});
  const int acc = static_cast<int>(b.doc["accessors"].size()) - 1;
  b.add_node({{"mesh", b.add_mesh("bomb", {{{"attributes", {{"POSITION", acc}}}}})}});
  expect_error(load(b.gltf_embedded(), budget_of(256 * kMiB)), StatusCode::kResourceExhausted,
               {"mesh 'bomb' (mesh[0]) primitive 0", "accessor 0 (POSITION)", "50331648 vertices",
                "GiB", "the import memory budget", "256.0 MiB"});
}

// EXT_mesh_gpu_instancing: a million instances from one TRANSLATION accessor
// without a bufferView. Measured against luxeld before the budget: +316 MB.
TEST(ImportBudget, InstancingBombIsRefusedNamingTheExtension) {
  GltfBuilder b = quad_scene();
  b.doc["accessors"].push_back({{"componentType", test::kFloat},
                                {"count", 1000000},
                                {"type", "VEC3"},
                                {"min", {0, 0, 0}},
                                {"max", {0, 0, 0}}});
  const int acc = static_cast<int>(b.doc["accessors"].size()) - 1;
  b.doc["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["TRANSLATION"] = acc;
  b.doc["extensionsUsed"] = {"EXT_mesh_gpu_instancing"};
  expect_error(load(b.gltf_embedded(), budget_of(64 * kMiB)), StatusCode::kResourceExhausted,
               {"node 'n' (node[0]) EXT_mesh_gpu_instancing", "1000000 instances", "MiB",
                "the import memory budget"});
  // A thousand instances fit the same budget.
  b.doc["accessors"][static_cast<size_t>(acc)]["count"] = 1000;
  auto ok = load(b.gltf_embedded(), budget_of(64 * kMiB));
  ASSERT_TRUE(ok.is_ok()) << ok.status().to_string();
  EXPECT_EQ(ok->instances.size(), 1000u);
}

// Four all-zero 16384 x 4000 PNGs (each ~65 KB, 65.5 million texels, under
// the per-image and total pixel limits): measured against luxeld before the
// budget, +1 GB per upload. Refused before stb_image allocates.
TEST(ImportBudget, ZeroPngBombIsRefusedNamingTheImage) {
  const int w = 16384, h = 4000;
  const std::string png = test::encode_png(w, h, 1, std::vector<uint8_t>(size_t(w) * h, 0));
  GltfBuilder b = quad_scene();
  b.doc["images"] = json::array();
  b.doc["textures"] = json::array();
  for (int i = 0; i < 4; ++i) {
    b.doc["images"].push_back({{"uri", "data:image/png;base64," + test::base64(png)}});
    b.doc["textures"].push_back({{"source", i}});
  }
  b.add_material(
      {{"pbrMetallicRoughness",
        {{"baseColorTexture", {{"index", 0}}}, {"metallicRoughnessTexture", {{"index", 1}}}}},
       {"emissiveTexture", {{"index", 2}}},
       {"occlusionTexture", {{"index", 3}}}});
  b.doc["meshes"][0]["primitives"][0]["material"] = 0;
  // Refused from the images' headers, before the first is decoded.
  expect_error(load(b.gltf_embedded(), budget_of(512 * kMiB)), StatusCode::kResourceExhausted,
               {"image 0 (16384 x 4000), image 1 (16384 x 4000), image 2 (16384 x 4000), image 3 "
                "(16384 x 4000)",
                "1000.0 MiB", "the import memory budget", "512.0 MiB"});
  // The four images' texels (1000 MiB) fit 1 GiB, but not with stb_image's
  // buffers for the third, whose decode is refused before it allocates.
  expect_error(load(b.gltf_embedded(), budget_of(1024 * kMiB)), StatusCode::kResourceExhausted,
               {"image 2", "16384 x 4000 texels", "8-bit, 1 channel", "the import memory budget",
                "1.0 GiB"});
  // Sizes only (decode_textures false): nothing to reserve.
  ImportOptions sizes = budget_of(512 * kMiB);
  sizes.decode_textures = false;
  EXPECT_TRUE(load(b.gltf_embedded(), sizes).is_ok());
}

// A PNG header claiming 65535 x 65535 is "too large" with the limit, not an
// "unknown image type" (stb_image's words for a header it will not decode).
TEST(ImportBudget, HugePngHeaderSaysTooLargeWithTheLimit) {
  std::string png = test::encode_png(1, 1, 4, std::vector<uint8_t>(4, 7));
  for (size_t i = 16; i < 24; ++i) png[i] = static_cast<char>(i % 4 < 2 ? 0x00 : 0xFF);
  GltfBuilder b = quad_scene();
  b.doc["images"] = json::array({{{"uri", "data:image/png;base64," + test::base64(png)}}});
  b.doc["textures"] = json::array({{{"source", 0}}});
  b.add_material({{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}});
  b.doc["meshes"][0]["primitives"][0]["material"] = 0;
  expect_error(load(b.gltf_embedded(), ImportOptions{}), StatusCode::kResourceExhausted,
               {"image 0", "65535 x 65535", "too large", "16384 per side"});
}

// The smallest budget that accepts a file is the peak it reserved: that
// budget accepts it, one byte less refuses it.
TEST(ImportBudget, FileJustUnderTheBudgetIsAccepted) {
  GltfBuilder b = quad_scene();
  const std::string png = test::encode_png(64, 32, 4, std::vector<uint8_t>(64 * 32 * 4, 9));
  b.doc["images"] = json::array({{{"uri", "data:image/png;base64," + test::base64(png)}}});
  b.doc["textures"] = json::array({{{"source", 0}}});
  b.add_material({{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}});
  b.doc["meshes"][0]["primitives"][0]["material"] = 0;
  const std::string file = b.gltf_embedded();
  auto big = load(file, budget_of(64 * kMiB));
  ASSERT_TRUE(big.is_ok()) << big.status().to_string();
  const uint64_t peak = big->import_stats.peak_reserved_bytes;
  // At least what it keeps: the file twice, the texels, the mesh arrays.
  EXPECT_GE(peak, 2 * file.size() + 64 * 32 * 4 + 4 * 40 + 2 * 20);
  EXPECT_TRUE(load(file, budget_of(peak)).is_ok());
  expect_error(load(file, budget_of(peak - 1)), StatusCode::kResourceExhausted,
               {"the import memory budget"});
}

// Concurrent imports share one pool (the daemon's): an import that does not
// fit next to what the others hold is refused naming the shared budget, and
// every import gives its bytes back when it ends.
TEST(ImportBudget, ImportsShareOnePool) {
  ImportMemoryPool pool(16 * kMiB, "the daemon's import memory budget (--import-memory-budget)");
  ImportOptions shared;
  shared.memory_pool = &pool;
  shared.max_import_bytes = 1;  // not used with a pool
  const std::string file = quad_scene().gltf_embedded();
  auto alone = load(file, shared);
  ASSERT_TRUE(alone.is_ok()) << alone.status().to_string();
  EXPECT_EQ(pool.in_use(), 0u);
  const uint64_t need = alone->import_stats.peak_reserved_bytes;
  ASSERT_GT(need, 0u);
  // Another import holds all but a little.
  ASSERT_TRUE(pool.try_reserve(pool.capacity() - need / 2));
  expect_error(
      load(file, shared), StatusCode::kResourceExhausted,
      {"the daemon's import memory budget (--import-memory-budget)", "16.0 MiB", "other imports"});
  EXPECT_EQ(pool.in_use(), pool.capacity() - need / 2);  // the refused one holds nothing
  pool.release(pool.capacity() - need / 2);
  EXPECT_TRUE(load(file, shared).is_ok());
  EXPECT_EQ(pool.in_use(), 0u);
}

TEST(ImportBudget, TimeoutEndsTheImport) {
  ImportOptions o;
  o.timeout_seconds = 0;  // past at the first check
  expect_error(load(quad_scene().gltf_embedded(), o), StatusCode::kDeadlineExceeded,
               {"test.gltf", "time limit of 0 s", "--import-timeout"});
  o.timeout_seconds = 300;
  EXPECT_TRUE(load(quad_scene().gltf_embedded(), o).is_ok());
}

TEST(ImportBudget, ParseByteSize) {
  EXPECT_EQ(parse_byte_size("3221225472").value(), uint64_t{3} << 30);
  EXPECT_EQ(parse_byte_size("3GiB").value(), uint64_t{3} << 30);
  EXPECT_EQ(parse_byte_size("512MiB").value(), uint64_t{512} << 20);
  EXPECT_EQ(parse_byte_size("64 KiB").value(), uint64_t{64} << 10);
  EXPECT_EQ(parse_byte_size("2GB").value(), uint64_t{2000000000});
  EXPECT_EQ(parse_byte_size("1.5GiB").value(), uint64_t{3} << 29);
  EXPECT_EQ(parse_byte_size("2e9").value(), uint64_t{2000000000});
  for (const char* bad : {"", "GiB", "1.5", "-1", "3 gigs", "1e30", "99999999999999999999",
                          "17179869184GiB", "2e9.5", "nan", "inf"}) {
    auto r = parse_byte_size(bad);
    EXPECT_FALSE(r.is_ok()) << bad;
    if (!r.is_ok()) EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  }
  EXPECT_GT(default_import_memory_budget(), 0u);
}

}  // namespace
}  // namespace luxel::scene
