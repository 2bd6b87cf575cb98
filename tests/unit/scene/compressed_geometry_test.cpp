// Compressed glTF geometry (scene/gltf_decompress.h) imported as the plain
// geometry it encodes, from files written by independent tools:
//  - KHR_draco_mesh_compression: Blender 5.0.1's glTF exporter (its Draco
//    encoder) exports one scene plain and compressed
//    (blender_compressed_export.py); both import to the same triangles
//    within Draco's quantisation;
//  - EXT_meshopt_compression: gltfpack 1.2 packs scenes/cornell_box.gltf
//    with and without -cc; the compressed file imports to exactly the
//    uncompressed one's triangles, and both to the original's within
//    gltfpack's 14-bit position quantisation;
//  - EXT_meshopt_compression written here with meshoptimizer's own encoder
//    (every mode and the octahedral filter), which needs no external tool.
// Corrupt streams and over-budget counts are refused, naming the primitive
// or bufferView.
#include <gtest/gtest.h>
#include <meshoptimizer.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "gltf_builder.h"
#include "scene/gltf_import.h"

namespace luxel::scene {
namespace {

using test::glb_json;
using test::read_all;

using nlohmann::json;
using test::GltfBuilder;
using test::TempDir;

// A GLB's JSON and BIN chunks, read and written here independently of the
// code under test, to edit files the tools wrote.
struct Glb {
  json doc;
  std::string bin;
};

Glb split_glb(const std::string& bytes) {
  uint32_t json_length = 0, bin_length = 0;
  std::memcpy(&json_length, bytes.data() + 12, 4);
  Glb g;
  g.doc = json::parse(bytes.substr(20, json_length));
  if (20 + json_length + 8 <= bytes.size()) {
    std::memcpy(&bin_length, bytes.data() + 20 + json_length, 4);
    g.bin = bytes.substr(20 + json_length + 8, bin_length);
  }
  return g;
}

std::string join_glb(const Glb& g) {
  std::string js = g.doc.dump();
  while (js.size() % 4) js.push_back(' ');
  std::string bin = g.bin;
  while (bin.size() % 4) bin.push_back('\0');
  std::string out;
  auto put = [&](uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
  put(0x46546C67);
  put(2);
  put(static_cast<uint32_t>(12 + 8 + js.size() + (bin.empty() ? 0 : 8 + bin.size())));
  put(static_cast<uint32_t>(js.size()));
  put(0x4E4F534A);
  out += js;
  if (!bin.empty()) {
    put(static_cast<uint32_t>(bin.size()));
    put(0x004E4942);
    out += bin;
  }
  return out;
}

struct Triangle {
  std::array<Vec3, 3> p;    // world space
  std::array<Vec3, 3> n;    // object-space normals
  std::array<Vec2, 3> uv1;  // lightmap UVs
  int instance = 0;
};

std::vector<Triangle> triangles(const Scene& s) {
  std::vector<Triangle> out;
  for (size_t i = 0; i < s.instances.size(); ++i) {
    const Instance& inst = s.instances[i];
    const Mesh& m = s.meshes[static_cast<size_t>(inst.mesh)];
    for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
      Triangle tri;
      tri.instance = static_cast<int>(i);
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = m.indices[t + static_cast<size_t>(k)];
        tri.p[static_cast<size_t>(k)] = transform_point(inst.object_to_world, m.positions[v]);
        tri.n[static_cast<size_t>(k)] = m.normals[v];
        tri.uv1[static_cast<size_t>(k)] = m.uv1[v];
      }
      out.push_back(tri);
    }
  }
  return out;
}

float dist(Vec3 a, Vec3 b) {
  return std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) +
                   (a.z - b.z) * (a.z - b.z));
}

struct Tolerance {
  float position = 0, normal = 0, uv = 0;
};

// Every triangle of `got` has a triangle of `want` of the same instance with
// the same corners (any rotation, same winding) within `tol`; the largest
// errors are returned through `worst`.
::testing::AssertionResult same_triangles(const std::vector<Triangle>& want,
                                          const std::vector<Triangle>& got, Tolerance tol,
                                          Tolerance* worst) {
  if (want.size() != got.size())
    return ::testing::AssertionFailure() << got.size() << " triangles, expected " << want.size();
  std::vector<bool> used(want.size(), false);
  for (size_t g = 0; g < got.size(); ++g) {
    bool found = false;
    for (size_t w = 0; w < want.size() && !found; ++w) {
      if (used[w] || want[w].instance != got[g].instance) continue;
      for (int r = 0; r < 3 && !found; ++r) {
        Tolerance e;
        for (size_t k = 0; k < 3; ++k) {
          const size_t j = (k + static_cast<size_t>(r)) % 3;
          e.position = std::max(e.position, dist(want[w].p[j], got[g].p[k]));
          e.normal = std::max(e.normal, dist(want[w].n[j], got[g].n[k]));
          e.uv = std::max(e.uv, std::max(std::fabs(want[w].uv1[j].x - got[g].uv1[k].x),
                                         std::fabs(want[w].uv1[j].y - got[g].uv1[k].y)));
        }
        if (e.position <= tol.position && e.normal <= tol.normal && e.uv <= tol.uv) {
          found = used[w] = true;
          worst->position = std::max(worst->position, e.position);
          worst->normal = std::max(worst->normal, e.normal);
          worst->uv = std::max(worst->uv, e.uv);
        }
      }
    }
    if (!found) {
      const Vec3 c = got[g].p[0];
      return ::testing::AssertionFailure()
             << "triangle " << g << " (instance " << got[g].instance << ", corner " << c.x << " "
             << c.y << " " << c.z << ") matches no expected triangle";
    }
  }
  return ::testing::AssertionSuccess();
}

void expect_error(const Result<Scene>& r, StatusCode code,
                  std::initializer_list<const char*> parts) {
  ASSERT_FALSE(r.is_ok()) << "imported, expected an error";
  EXPECT_EQ(r.status().code(), code) << r.status().to_string();
  std::printf("refused: %s\n", r.status().message().c_str());
  for (const char* p : parts)
    EXPECT_NE(r.status().message().find(p), std::string::npos)
        << "'" << p << "' not in: " << r.status().message();
}

// ---- KHR_draco_mesh_compression, written by Blender ----------------------

class DracoBlender : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const char* python = std::getenv("LUXEL_BPY_PYTHON");
    const char* script = std::getenv("LUXEL_BLENDER_COMPRESSED_SCRIPT");
    if (!python || !*python || !script) return;
    dir_ = new TempDir;
    const std::string cmd = std::string("'") + python + "' '" + script + "' -- '" + dir_->path() +
                            "' > '" + dir_->path() + "/blender.log' 2>&1";
    if (std::system(cmd.c_str()) != 0) {
      delete dir_;
      dir_ = nullptr;
    }
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  void SetUp() override {
    const char* python = std::getenv("LUXEL_BPY_PYTHON");
    if (!python || !*python) GTEST_SKIP() << "LUXEL_BPY_PYTHON is not set";
    ASSERT_NE(dir_, nullptr) << "blender_compressed_export.py failed";
  }
  static std::string path(const char* name) { return dir_->path() + "/" + name; }
  static TempDir* dir_;
};
TempDir* DracoBlender::dir_ = nullptr;

TEST_F(DracoBlender, ImportsTheSameTrianglesWithinQuantisation) {
  auto plain = import_gltf_file(path("plain.glb"));
  auto draco = import_gltf_file(path("draco.glb"));
  ASSERT_TRUE(plain) << plain.status().to_string();
  ASSERT_TRUE(draco) << draco.status().to_string();
  for (const std::string& w : draco->import_stats.warnings) ADD_FAILURE() << w;
  ASSERT_EQ(plain->instances.size(), 3u);
  ASSERT_EQ(draco->instances.size(), 3u);
  for (const Mesh& m : draco->meshes) EXPECT_TRUE(m.has_lightmap_uvs) << m.name;
  // Blender's default Draco quantisation: positions 14 bits over each mesh's
  // bounding box (error at most half a step per axis, under extent / 2^14
  // in length), normals 10 bits, texture coordinates 12 bits over their
  // range ([0, 1] here).
  float extent = 0;
  for (const Mesh& m : plain->meshes) {
    Vec3 lo = m.positions[0], hi = m.positions[0];
    for (const Vec3& p : m.positions)
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
    for (int k = 0; k < 3; ++k) extent = std::max(extent, hi[k] - lo[k]);
  }
  const Tolerance tol{extent / 16384.0f, 4.0f / 1024.0f, 1.0f / 4096.0f};
  Tolerance worst;
  EXPECT_TRUE(same_triangles(triangles(*plain), triangles(*draco), tol, &worst));
  std::printf(
      "Draco vs plain: %zu triangles; largest error: position %.3g (bound %.3g), normal "
      "%.3g, uv %.3g\n",
      triangles(*draco).size(), worst.position, tol.position, worst.normal, worst.uv);
  EXPECT_GT(worst.position, 0.0f) << "quantised, so not bit-identical";
}

TEST_F(DracoBlender, TruncatedBitstreamIsNamed) {
  Glb g = split_glb(read_all(path("draco.glb")));
  json& prim = g.doc["meshes"][1]["primitives"][0];
  const int view = prim["extensions"]["KHR_draco_mesh_compression"]["bufferView"];
  json& v = g.doc["bufferViews"][static_cast<size_t>(view)];
  v["byteLength"] = v["byteLength"].get<int>() / 2;
  const std::string mesh = g.doc["meshes"][1]["name"];
  expect_error(import_gltf_memory(join_glb(g), "", "cut.glb"), StatusCode::kInvalidArgument,
               {"cut.glb", ("mesh '" + mesh + "'").c_str(), "primitive 0",
                "KHR_draco_mesh_compression", "does not decode"});
}

TEST_F(DracoBlender, DeclaredCountThatDiffersIsNamed) {
  Glb g = split_glb(read_all(path("draco.glb")));
  const json& prim = g.doc["meshes"][2]["primitives"][0];
  const size_t pos = prim["attributes"]["POSITION"];
  g.doc["accessors"][pos]["count"] = g.doc["accessors"][pos]["count"].get<int>() + 1;
  expect_error(import_gltf_memory(join_glb(g), "", "count.glb"), StatusCode::kInvalidArgument,
               {"primitive 0", "attribute POSITION", "declares count", "decodes to"});
}

TEST_F(DracoBlender, ElementBudgetRefusesBeforeDecoding) {
  ImportOptions options;
  options.max_accessor_elements = 1000;  // the sphere alone declares more
  expect_error(import_gltf_file(path("draco.glb"), options), StatusCode::kResourceExhausted,
               {"KHR_draco_mesh_compression", "element limit"});
}

// ---- EXT_meshopt_compression, written by gltfpack ------------------------

class GltfpackMeshopt : public ::testing::Test {
 protected:
  void SetUp() override {
    const char* g = std::getenv("LUXEL_GLTFPACK");
    if (!g || !*g)
      GTEST_SKIP() << "LUXEL_GLTFPACK is not set (tests/support/install-test-tools.sh)";
    gltfpack_ = g;
    source_ = std::string(LUXEL_SCENES_DIR) + "/cornell_box.gltf";
  }
  // gltfpack `flags` on the Cornell box into dir_/name.
  std::string pack(const std::string& name, const std::string& flags) {
    const std::string out = dir_.path() + "/" + name;
    const std::string cmd =
        "'" + gltfpack_ + "' -i '" + source_ + "' -o '" + out + "' " + flags + " > /dev/null 2>&1";
    EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
    return out;
  }
  std::string gltfpack_, source_;
  TempDir dir_;
};

TEST_F(GltfpackMeshopt, CompressedImportsExactlyAsUncompressed) {
  const std::string packed = pack("packed.glb", "");
  const std::string compressed = pack("compressed.glb", "-cc");
  const Glb c = split_glb(read_all(compressed));
  ASSERT_NE(c.doc.dump().find("\"EXT_meshopt_compression\""), std::string::npos);
  ASSERT_NE(c.doc.dump().find("\"OCTAHEDRAL\""), std::string::npos) << "normals use the filter";
  auto a = import_gltf_file(packed);
  auto b = import_gltf_file(compressed);
  ASSERT_TRUE(a) << a.status().to_string();
  ASSERT_TRUE(b) << b.status().to_string();
  for (const std::string& w : b->import_stats.warnings) ADD_FAILURE() << w;
  ASSERT_EQ(a->meshes.size(), b->meshes.size());
  for (size_t m = 0; m < a->meshes.size(); ++m) {
    const Mesh &x = a->meshes[m], &y = b->meshes[m];
    EXPECT_EQ(x.indices, y.indices);
    ASSERT_EQ(x.positions.size(), y.positions.size());
    for (size_t v = 0; v < x.positions.size(); ++v)
      for (int k = 0; k < 3; ++k) EXPECT_EQ(x.positions[v][k], y.positions[v][k]) << v;
    // The octahedral filter (8 bits) against gltfpack's plain 8-bit normals.
    for (size_t v = 0; v < x.normals.size(); ++v)
      EXPECT_LT(dist(x.normals[v], y.normals[v]), 2.0f / 127.0f) << v;
  }
}

TEST_F(GltfpackMeshopt, MatchesTheOriginalWithinQuantisation) {
  auto original = import_gltf_file(source_);
  auto compressed = import_gltf_file(pack("compressed.glb", "-cc"));
  ASSERT_TRUE(original) << original.status().to_string();
  ASSERT_TRUE(compressed) << compressed.status().to_string();
  // gltfpack merges the scene into one mesh of one node; compare the world
  // triangles as one set. Positions: 14 bits over the scene's extent.
  auto world = [](const Scene& s) {
    auto t = triangles(s);
    for (auto& tri : t) tri.instance = 0, tri.uv1 = {}, tri.n = {};
    return t;
  };
  float extent = 0;
  const auto want = world(*original);
  Vec3 lo = want[0].p[0], hi = lo;
  for (const Triangle& t : want)
    for (const Vec3& p : t.p)
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
  for (int k = 0; k < 3; ++k) extent = std::max(extent, hi[k] - lo[k]);
  // Half a step of 14 bits per axis over the scene's extent: under
  // extent / 2^14 in length.
  Tolerance worst;
  EXPECT_TRUE(same_triangles(want, world(*compressed), {extent / 16384.0f, 0, 0}, &worst));
  std::printf("gltfpack -cc vs cornell_box.gltf: largest position error %.3g (bound %.3g)\n",
              worst.position, extent / 16384.0f);
}

TEST_F(GltfpackMeshopt, FallbackFileIsNotRead) {
  const std::string with_fallback = pack("fallback.glb", "-cf");
  const Glb g = split_glb(read_all(with_fallback));
  const std::string uri = g.doc["buffers"][1]["uri"];
  ASSERT_TRUE(std::filesystem::remove(dir_.path() + "/" + uri)) << uri;
  auto a = import_gltf_file(pack("compressed.glb", "-cc"));
  auto b = import_gltf_file(with_fallback);
  ASSERT_TRUE(a) << a.status().to_string();
  ASSERT_TRUE(b) << b.status().to_string();
  ASSERT_EQ(a->meshes.size(), b->meshes.size());
  for (size_t m = 0; m < a->meshes.size(); ++m)
    EXPECT_EQ(a->meshes[m].indices, b->meshes[m].indices);
}

// ---- EXT_meshopt_compression, written with meshoptimizer's encoder --------

// A wavy n x n grid: positions (float), unit normals, triangle indices.
struct Grid {
  std::vector<float> pos, nrm4;  // nrm4: xyz + 0 per vertex (the filter encoder's input)
  std::vector<uint32_t> idx;
};

Grid make_grid(int n) {
  Grid g;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const float x = static_cast<float>(i) / static_cast<float>(n - 1);
      const float z = static_cast<float>(j) / static_cast<float>(n - 1);
      const float y = 0.1f * std::sin(6.0f * x) * std::cos(4.0f * z);
      const float dx = 0.6f * std::cos(6.0f * x) * std::cos(4.0f * z);
      const float dz = -0.4f * std::sin(6.0f * x) * std::sin(4.0f * z);
      const float len = std::sqrt(dx * dx + 1 + dz * dz);
      g.pos.insert(g.pos.end(), {x, y, z});
      g.nrm4.insert(g.nrm4.end(), {-dx / len, 1 / len, -dz / len, 0});
    }
  }
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {
      const auto v = static_cast<uint32_t>(j * n + i), w = static_cast<uint32_t>(n);
      g.idx.insert(g.idx.end(), {v, v + w, v + 1, v + 1, v + w, v + w + 1});
    }
  }
  return g;
}

class MeshoptEncoded : public ::testing::Test {
 protected:
  // The grid as a .glb whose three views are EXT_meshopt_compression views
  // of a fallback buffer without data: positions (ATTRIBUTES), normals
  // (ATTRIBUTES + OCTAHEDRAL, int8 normalized) and indices (`index_mode`).
  // `compressed_views` receives the views' indices.
  static std::string file(const Grid& g, const char* index_mode, std::vector<int>* views) {
    GltfBuilder b;
    size_t fallback = 0;
    const size_t count = g.pos.size() / 3;
    auto add = [&](const std::vector<uint8_t>& data, size_t n, size_t stride, const char* mode,
                   const char* filter, int target) {
      while (b.bin.size() % 4) b.bin.push_back(0);
      json ext = {{"buffer", 0},
                  {"byteOffset", b.bin.size()},
                  {"byteLength", data.size()},
                  {"byteStride", stride},
                  {"count", n},
                  {"mode", mode}};
      if (filter) ext["filter"] = filter;
      b.bin.insert(b.bin.end(), data.begin(), data.end());
      json view = {{"buffer", 1},
                   {"byteOffset", fallback},
                   {"byteLength", n * stride},
                   {"target", target},
                   {"extensions", {{"EXT_meshopt_compression", ext}}}};
      if (target == 34962) view["byteStride"] = stride;
      fallback += (n * stride + 3) / 4 * 4;
      b.doc["bufferViews"].push_back(view);
      views->push_back(static_cast<int>(b.doc["bufferViews"].size()) - 1);
      return views->back();
    };
    std::vector<uint8_t> enc(meshopt_encodeVertexBufferBound(count, 12));
    enc.resize(meshopt_encodeVertexBuffer(enc.data(), enc.size(), g.pos.data(), count, 12));
    const int pos_view = add(enc, count, 12, "ATTRIBUTES", nullptr, 34962);
    std::vector<int8_t> oct(count * 4);
    meshopt_encodeFilterOct(oct.data(), count, 4, 8, g.nrm4.data());
    enc.assign(meshopt_encodeVertexBufferBound(count, 4), 0);
    enc.resize(meshopt_encodeVertexBuffer(enc.data(), enc.size(), oct.data(), count, 4));
    const int nrm_view = add(enc, count, 4, "ATTRIBUTES", "OCTAHEDRAL", 34962);
    if (std::string(index_mode) == "TRIANGLES") {
      enc.assign(meshopt_encodeIndexBufferBound(g.idx.size(), count), 0);
      enc.resize(meshopt_encodeIndexBuffer(enc.data(), enc.size(), g.idx.data(), g.idx.size()));
    } else {
      enc.assign(meshopt_encodeIndexSequenceBound(g.idx.size(), count), 0);
      enc.resize(meshopt_encodeIndexSequence(enc.data(), enc.size(), g.idx.data(), g.idx.size()));
    }
    const int idx_view = add(enc, g.idx.size(), 4, index_mode, nullptr, 34963);
    json prim;
    const int pa = b.add_accessor(pos_view, test::kFloat, count, "VEC3");
    b.doc["accessors"][static_cast<size_t>(pa)]["min"] = {0, -0.1, 0};
    b.doc["accessors"][static_cast<size_t>(pa)]["max"] = {1, 0.1, 1};
    prim["attributes"]["POSITION"] = pa;
    // The filter's output: int8 normalized (x, y, z, w); VEC3 reads xyz of
    // each 4-byte element through the view's stride.
    prim["attributes"]["NORMAL"] = b.add_accessor(nrm_view, test::kByte, count, "VEC3", 0, true);
    prim["indices"] = b.add_accessor(idx_view, test::kUInt, g.idx.size(), "SCALAR");
    b.add_node({{"mesh", b.add_mesh("grid", {prim})}});
    b.doc["extensionsUsed"] = {"EXT_meshopt_compression"};
    b.doc["extensionsRequired"] = {"EXT_meshopt_compression"};
    Glb glb = split_glb(b.glb());
    glb.doc["buffers"].push_back(
        {{"byteLength", fallback},
         {"extensions", {{"EXT_meshopt_compression", {{"fallback", true}}}}}});
    return join_glb(glb);
  }
};

TEST_F(MeshoptEncoded, EveryModeDecodesToTheEncodedData) {
  const Grid g = make_grid(17);
  for (const char* mode : {"TRIANGLES", "INDICES"}) {
    SCOPED_TRACE(mode);
    std::vector<int> views;
    auto r = import_gltf_memory(file(g, mode, &views), "", "grid.glb");
    ASSERT_TRUE(r) << r.status().to_string();
    for (const std::string& w : r->import_stats.warnings) ADD_FAILURE() << w;
    ASSERT_EQ(r->meshes.size(), 1u);
    const Mesh& m = r->meshes[0];
    ASSERT_EQ(m.positions.size(), g.pos.size() / 3);
    for (size_t v = 0; v < m.positions.size(); ++v)
      for (int k = 0; k < 3; ++k)
        ASSERT_EQ(m.positions[v][k], g.pos[3 * v + static_cast<size_t>(k)]);
    EXPECT_EQ(m.indices, g.idx);
    float worst = 0;
    for (size_t v = 0; v < m.normals.size(); ++v)
      worst = std::max(worst,
                       dist(m.normals[v], {g.nrm4[4 * v], g.nrm4[4 * v + 1], g.nrm4[4 * v + 2]}));
    EXPECT_LT(worst, 0.03f) << "8-bit octahedral normals";
  }
}

TEST_F(MeshoptEncoded, CorruptViewIsNamed) {
  const Grid g = make_grid(17);
  std::vector<int> views;
  Glb glb = split_glb(file(g, "TRIANGLES", &views));
  // The positions' compressed data cut short: the tail block (the README's
  // "Mode 0: attributes") is missing.
  json& ext = glb.doc["bufferViews"][static_cast<size_t>(views[0])]["extensions"]
                     ["EXT_meshopt_compression"];
  ext["byteLength"] = ext["byteLength"].get<int>() / 2;
  expect_error(import_gltf_memory(join_glb(glb), "", "grid.glb"), StatusCode::kInvalidArgument,
               {"grid.glb", ("bufferViews[" + std::to_string(views[0]) + "]").c_str(),
                "EXT_meshopt_compression", "ATTRIBUTES data does not decode"});
  // Garbage in place of the index stream.
  glb = split_glb(file(g, "TRIANGLES", &views));
  const json& ie = glb.doc["bufferViews"][static_cast<size_t>(views.back())]["extensions"]
                          ["EXT_meshopt_compression"];
  std::memset(glb.bin.data() + ie["byteOffset"].get<size_t>(), 0x55, 1);
  expect_error(import_gltf_memory(join_glb(glb), "", "grid.glb"), StatusCode::kInvalidArgument,
               {("bufferViews[" + std::to_string(views.back()) + "]").c_str(),
                "TRIANGLES data does not decode"});
}

TEST_F(MeshoptEncoded, InvalidExtensionObjectsAreNamed) {
  const Grid g = make_grid(5);
  std::vector<int> views;
  Glb glb = split_glb(file(g, "TRIANGLES", &views));
  glb.doc["bufferViews"][static_cast<size_t>(views[0])]["extensions"]["EXT_meshopt_compression"]
         ["count"] = 1000;
  expect_error(import_gltf_memory(join_glb(glb), "", "grid.glb"), StatusCode::kInvalidArgument,
               {"bufferViews[", "is not the bufferView's byteLength"});
  glb = split_glb(file(g, "TRIANGLES", &views));
  glb.doc["bufferViews"][static_cast<size_t>(views[2])]["extensions"]["EXT_meshopt_compression"]
         ["filter"] = "OCTAHEDRAL";
  expect_error(import_gltf_memory(join_glb(glb), "", "grid.glb"), StatusCode::kInvalidArgument,
               {"mode TRIANGLES allows no filter"});
  // A view of the fallback buffer without the extension (the README's
  // "Fallback buffers": only compressed views refer to it).
  glb = split_glb(file(g, "TRIANGLES", &views));
  glb.doc["bufferViews"][static_cast<size_t>(views[1])].erase("extensions");
  expect_error(import_gltf_memory(join_glb(glb), "", "grid.glb"), StatusCode::kInvalidArgument,
               {"fallback buffer", "not compressed"});
}

TEST_F(MeshoptEncoded, ElementBudgetRefusesBeforeDecoding) {
  const Grid g = make_grid(64);  // 4096 vertices
  std::vector<int> views;
  ImportOptions options;
  options.max_accessor_elements = 4000;
  expect_error(import_gltf_memory(file(g, "TRIANGLES", &views), "", "grid.glb", options),
               StatusCode::kResourceExhausted,
               {("bufferViews[" + std::to_string(views[0]) + "]").c_str(), "element limit"});
}

}  // namespace
}  // namespace luxel::scene
