// Valid glTF 2.0 features the importer once refused or dropped, and invalid
// files it once accepted or reported without naming the file and object.
// Each case is a small document built in memory.
#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <random>

#include "common/clock.h"
#include "gltf_builder.h"
#include "scene/gltf_import.h"
#include "scene/scene_stats.h"

namespace luxel::scene {
namespace {

using test::GltfBuilder;
using test::json;
using test::kQuadIndices;
using test::kQuadPositions;

Result<Scene> load(const std::string& bytes, const std::string& name = "conf.gltf") {
  return import_gltf_memory(bytes, "", name);
}

void expect_error(const Result<Scene>& r, StatusCode code,
                  std::initializer_list<const char*> needles) {
  ASSERT_FALSE(r.is_ok());
  EXPECT_EQ(r.status().code(), code) << r.status().to_string();
  for (const char* n : needles)
    EXPECT_NE(r.status().message().find(n), std::string::npos)
        << "'" << n << "' not in: " << r.status().message();
}

bool has_warning(const Scene& s, const char* needle) {
  for (const auto& w : s.import_stats.warnings)
    if (w.find(needle) != std::string::npos) return true;
  return false;
}

// z of the face normal of triangle t (positions in the XY plane).
float winding_z(const Mesh& m, size_t t) {
  const Vec3 a = m.positions[m.indices[3 * t]], b = m.positions[m.indices[3 * t + 1]],
             c = m.positions[m.indices[3 * t + 2]];
  return cross(b - a, c - a).z;
}

// A strip of 4 triangles over a 2 x 1 row of quads, and a fan of 4 triangles
// around the origin, all counter-clockwise seen from +Z.
const std::vector<float> kStrip = {0, 0, 0, 0, 1, 0, 1, 0, 0, 1, 1, 0, 2, 0, 0, 2, 1, 0};
const std::vector<float> kFan = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, -1, 1, 0, -1, 0, 0};

TEST(SceneConformance, StripsAndFansBecomeTrianglesWithConsistentWinding) {
  for (int mode : {5, 6}) {
    for (bool indexed : {false, true}) {
      GltfBuilder b;
      const auto& pos = mode == 5 ? kStrip : kFan;
      // Indexed: the strip with each pair swapped, the fan walked the other way.
      std::vector<uint32_t> idx = {0, 5, 4, 3, 2, 1};
      if (mode == 5) idx = {1, 0, 3, 2, 5, 4};
      json prim = indexed ? b.triangles(pos, idx) : b.triangles(pos);
      prim["mode"] = mode;
      b.add_node({{"mesh", b.add_mesh("m", {prim})}});
      auto r = load(b.gltf_embedded());
      ASSERT_TRUE(r.is_ok()) << r.status().to_string();
      ASSERT_EQ(r->meshes.size(), 1u);
      const Mesh& m = r->meshes[0];
      ASSERT_EQ(m.triangle_count(), 4u) << "mode " << mode << " indexed " << indexed;
      EXPECT_EQ(r->import_stats.skipped_primitives, 0u);
      // Every triangle has the same winding as the first one.
      const float first = winding_z(m, 0);
      EXPECT_NE(first, 0.0f);
      for (size_t t = 1; t < 4; ++t)
        EXPECT_GT(winding_z(m, t) * first, 0.0f) << "mode " << mode << " triangle " << t;
    }
  }
}

TEST(SceneConformance, PointsAndLinesSkippedBeforeTheLightmapUvCheck) {
  GltfBuilder b;
  json points = b.triangles(kQuadPositions, {}, test::kUInt, /*with_uv1=*/false);
  points["mode"] = 0;
  json lines = b.triangles(kQuadPositions, {0, 1, 1, 2}, test::kUInt, /*with_uv1=*/false);
  lines["mode"] = 1;
  b.add_node(
      {{"mesh", b.add_mesh("wire", {points, b.triangles(kQuadPositions, kQuadIndices), lines})}});
  auto r = load(b.gltf_embedded());
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  EXPECT_EQ(r->meshes[0].triangle_count(), 2u);
  EXPECT_EQ(r->import_stats.skipped_primitives, 2u);
  EXPECT_TRUE(has_warning(*r, "primitive 0: mode 0 (POINTS)"));
  EXPECT_TRUE(has_warning(*r, "primitive 2: mode 1 (LINES)"));
}

TEST(SceneConformance, RequiredExtensionsAndVersions) {
  GltfBuilder b;
  b.add_node({{"mesh", b.add_mesh("q", {b.triangles(kQuadPositions, kQuadIndices)})}});
  b.doc["extensionsUsed"] = {"KHR_mesh_quantization", "EXT_foo"};
  b.doc["extensionsRequired"] = {"KHR_mesh_quantization"};
  ASSERT_TRUE(load(b.gltf_embedded()).is_ok());
  b.doc["extensionsRequired"] = {"KHR_mesh_quantization", "EXT_foo"};
  expect_error(load(b.gltf_embedded()), StatusCode::kInvalidArgument,
               {"conf.gltf", "EXT_foo", "required"});
  b.doc.erase("extensionsRequired");

  b.doc["asset"]["minVersion"] = "2.1";
  expect_error(load(b.gltf_embedded()), StatusCode::kInvalidArgument, {"minVersion", "2.1"});
  b.doc["asset"]["minVersion"] = "2.0";
  ASSERT_TRUE(load(b.gltf_embedded()).is_ok());
  b.doc["asset"].erase("minVersion");

  // A glTF 1.0 document (meshes keyed by name) used to load as an empty scene.
  const std::string v1 =
      R"({"asset": {"version": "1.0"}, "meshes": {"m": {"primitives": []}}, "scene": "s",)"
      R"( "scenes": {"s": {"nodes": []}}})";
  expect_error(load(v1), StatusCode::kInvalidArgument,
               {"conf.gltf", "glTF 1.0 is not supported", "convert", "2.0"});
  b.doc["asset"]["version"] = "3.0";
  expect_error(load(b.gltf_embedded()), StatusCode::kInvalidArgument, {"3.0"});
}

TEST(SceneConformance, QuantizedAttributes) {
  GltfBuilder b;
  // POSITION as unnormalized shorts, NORMAL as normalized bytes, TEXCOORD_1
  // as unnormalized unsigned bytes and TEXCOORD_0 as normalized shorts.
  const int16_t pos[] = {0, 0, 0, 3, 0, 0, 3, 3, 0, 0, 3, 0};  // 4 x VEC3, 2-byte padded rows
  std::vector<int16_t> pos_padded;
  for (int v = 0; v < 4; ++v)
    pos_padded.insert(pos_padded.end(), {pos[3 * v], pos[3 * v + 1], pos[3 * v + 2], 0});
  const int8_t nrm[] = {0, 0, 127, 0, 0, 0, 127, 0, 0, 0, 127, 0, 0, 0, 127, 0};
  const uint8_t uv1[] = {0, 0, 2, 0, 2, 2, 0, 2};
  const int16_t uv0[] = {0, 0, 32767, 0, 32767, -32767, 0, -32768};
  json prim;
  prim["attributes"]["POSITION"] =
      b.add_accessor(b.add_view(pos_padded.data(), 32, 8), test::kShort, 4, "VEC3");
  prim["attributes"]["NORMAL"] =
      b.add_accessor(b.add_view(nrm, 16, 4), test::kByte, 4, "VEC3", 0, true);
  prim["attributes"]["TEXCOORD_1"] = b.add_accessor(b.add_view(uv1, 8), test::kUByte, 4, "VEC2");
  prim["attributes"]["TEXCOORD_0"] =
      b.add_accessor(b.add_view(uv0, 16), test::kShort, 4, "VEC2", 0, true);
  prim["indices"] = b.add_indices(kQuadIndices);
  b.add_node({{"mesh", b.add_mesh("q", {prim})}});
  b.doc["extensionsUsed"] = {"KHR_mesh_quantization"};
  b.doc["extensionsRequired"] = {"KHR_mesh_quantization"};
  auto r = load(b.gltf_embedded());
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  const Mesh& m = r->meshes[0];
  EXPECT_FLOAT_EQ(m.positions[2].x, 3.0f);
  EXPECT_FLOAT_EQ(m.positions[2].y, 3.0f);
  EXPECT_FLOAT_EQ(m.normals[1].z, 1.0f);
  EXPECT_FLOAT_EQ(m.uv1[2].x, 2.0f);
  EXPECT_FLOAT_EQ(m.uv0[1].x, 1.0f);
  EXPECT_FLOAT_EQ(m.uv0[3].y, -1.0f);  // -32768 clamps to -1
  EXPECT_FALSE(has_warning(*r, "KHR_mesh_quantization"));

  // Normals are never unnormalized integers (the extension's table).
  b.doc["accessors"][prim["attributes"]["NORMAL"].get<int>()]["normalized"] = false;
  expect_error(load(b.gltf_embedded()), StatusCode::kInvalidArgument,
               {"(NORMAL)", "must be normalized"});
}

TEST(SceneConformance, GpuInstancingMakesOneInstancePerElement) {
  GltfBuilder b;
  const int mesh = b.add_mesh("cube", {b.triangles(kQuadPositions, kQuadIndices)});
  // 3 instances: translations along x; the second one rotated 90 degrees
  // about z; the third scaled by 2.
  const int t = b.add_floats({1, 0, 0, 2, 0, 0, 3, 0, 0}, "VEC3");
  const float h = std::sqrt(0.5f);
  const int q = b.add_floats({0, 0, 0, 1, 0, 0, h, h, 0, 0, 0, 1}, "VEC4");
  const int s = b.add_floats({1, 1, 1, 1, 1, 1, 2, 2, 2}, "VEC3");
  json node = {{"mesh", mesh},
               {"name", "grid"},
               {"translation", {0, 10, 0}},
               {"extensions",
                {{"EXT_mesh_gpu_instancing",
                  {{"attributes", {{"TRANSLATION", t}, {"ROTATION", q}, {"SCALE", s}}}}}}}};
  b.add_node(node);
  b.doc["extensionsUsed"] = {"EXT_mesh_gpu_instancing"};
  b.doc["extensionsRequired"] = {"EXT_mesh_gpu_instancing"};
  auto r = load(b.gltf_embedded());
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  ASSERT_EQ(r->meshes.size(), 1u);
  ASSERT_EQ(r->instances.size(), 3u);
  EXPECT_EQ(r->instances[2].name, "node 'grid' instance 2");
  auto at = [&](size_t i, Vec3 p) { return transform_point(r->instances[i].object_to_world, p); };
  // node world (translation y + 10) * instance TRS.
  const Vec3 p0 = at(0, {1, 0, 0}), p1 = at(1, {1, 0, 0}), p2 = at(2, {1, 0, 0});
  EXPECT_NEAR(p0.x, 2, 1e-6);
  EXPECT_NEAR(p0.y, 10, 1e-6);
  EXPECT_NEAR(p1.x, 2, 1e-6);  // (1,0,0) rotated to (0,1,0), then + (2, 10, 0)
  EXPECT_NEAR(p1.y, 11, 1e-6);
  EXPECT_NEAR(p2.x, 5, 1e-6);  // scaled to (2,0,0), then + (3, 10, 0)
  EXPECT_NEAR(p2.y, 10, 1e-6);

  // Attributes of different counts are an error naming the node.
  b.doc["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["SCALE"] =
      b.add_floats({1, 1, 1}, "VEC3");
  expect_error(load(b.gltf_embedded()), StatusCode::kInvalidArgument,
               {"node 'grid' (node[0])", "EXT_mesh_gpu_instancing", "SCALE"});

  // An accessor index past int (JSON has no integer limit; tinygltf keeps it
  // as a double) or with a fraction is an error naming the attribute, not a
  // conversion (tests/fuzz/regressions/instancing_accessor_index_1e50.gltf).
  for (const json& index : {json(1.1e50), json(1.5)}) {
    b.doc["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["ROTATION"] = index;
    expect_error(load(b.gltf_embedded()), StatusCode::kInvalidArgument,
                 {"node 'grid' (node[0])", "ROTATION", "is not an integer"});
  }
}

// KHR_draco_mesh_compression is decoded (scene/gltf_decompress.h;
// compressed_geometry_test reads Blender's files): bytes that are not a
// Draco bitstream are an error naming the primitive, whether the file
// requires the extension or only uses it.
TEST(SceneConformance, DracoGarbageBitstreamIsNamed) {
  GltfBuilder b;
  // As exporters write it: accessors without bufferView, data in the extension.
  json prim = {{"attributes",
                {{"POSITION", b.add_accessor(-1, test::kFloat, 4, "VEC3")},
                 {"TEXCOORD_1", b.add_accessor(-1, test::kFloat, 4, "VEC2")}}},
               {"indices", b.add_accessor(-1, test::kUShort, 6, "SCALAR")},
               {"extensions",
                {{"KHR_draco_mesh_compression",
                  {{"bufferView", b.add_view(kQuadIndices.data(), 24)},
                   {"attributes", {{"POSITION", 0}, {"TEXCOORD_1", 1}}}}}}}};
  b.add_node({{"mesh", b.add_mesh("d", {prim})}});
  b.doc["extensionsUsed"] = {"KHR_draco_mesh_compression"};
  expect_error(load(b.gltf_embedded()), StatusCode::kInvalidArgument,
               {"conf.gltf", "mesh 'd' (mesh[0]) primitive 0", "KHR_draco_mesh_compression",
                "Draco bitstream in bufferView 0 does not decode"});
  b.doc["extensionsRequired"] = {"KHR_draco_mesh_compression"};
  expect_error(load(b.gltf_embedded()), StatusCode::kInvalidArgument,
               {"mesh 'd' (mesh[0]) primitive 0", "does not decode"});
}

TEST(SceneConformance, AccessorsWithoutBufferView) {
  GltfBuilder b;
  json prim = b.triangles(kQuadPositions, kQuadIndices);
  // TEXCOORD_0 without a bufferView: all zeros.
  prim["attributes"]["TEXCOORD_0"] = b.add_accessor(-1, test::kFloat, 4, "VEC2");
  // Indices without a bufferView, sparse only: zeros with 0 1 2 0 2 3 put in
  // at positions 0..5 (all of them, to make two triangles).
  const uint8_t where[] = {0, 1, 2, 3, 4, 5, 0, 0};
  const uint16_t what[] = {0, 1, 2, 0, 2, 3};
  const int idx = b.add_accessor(-1, test::kUShort, 6, "SCALAR");
  b.doc["accessors"][idx]["sparse"] = {
      {"count", 6},
      {"indices", {{"bufferView", b.add_view(where, 8)}, {"componentType", test::kUByte}}},
      {"values", {{"bufferView", b.add_view(what, 12)}}}};
  prim["indices"] = idx;
  b.add_node({{"mesh", b.add_mesh("q", {prim})}});
  for (const std::string& bytes : {b.gltf_embedded(), b.glb()}) {
    auto r = load(bytes);
    ASSERT_TRUE(r.is_ok()) << r.status().to_string();
    const Mesh& m = r->meshes[0];
    ASSERT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
    EXPECT_EQ(m.uv0[2].x, 0.0f);
  }
}

TEST(SceneConformance, UnusedBufferWithoutUriAndTextureWithoutSource) {
  GltfBuilder b;
  b.add_node({{"mesh", b.add_mesh("q", {b.triangles(kQuadPositions, kQuadIndices)})}});
  b.doc["textures"] = json::array({json::object()});
  b.add_material({{"name", "m"}, {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}});
  b.doc["meshes"][0]["primitives"][0]["material"] = 0;
  json doc = json::parse(b.gltf_embedded());
  doc["buffers"].push_back({{"byteLength", 64}});  // unused, no uri
  auto r = load(doc.dump());
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  EXPECT_EQ(r->materials[0].base_color_texture.texture, -1);
  EXPECT_TRUE(has_warning(*r, "texture 0 has no source"))
      << ::testing::PrintToString(r->import_stats.warnings);

  // A used buffer without uri is reported when read, naming the buffer.
  doc["bufferViews"][0]["buffer"] = 1;
  expect_error(load(doc.dump()), StatusCode::kInvalidArgument,
               {"conf.gltf", "buffer 1", "no data", "no uri"});
}

TEST(SceneConformance, MalformedDataUrisAreNamed) {
  GltfBuilder b;
  b.add_node({{"mesh", b.add_mesh("q", {b.triangles(kQuadPositions, kQuadIndices)})}});
  json doc = json::parse(b.gltf_embedded());
  const std::string good = doc["buffers"][0]["uri"];
  for (const std::string& bad :
       {std::string("data:application/octet-stream;base64"),  // no comma
        std::string("data:application/octet-stream,AAAA"),    // not base64
        "data:application/octet-stream;base64,**" + good.substr(good.find(',') + 3)}) {
    doc["buffers"][0]["uri"] = bad;
    expect_error(load(doc.dump()), StatusCode::kInvalidArgument,
                 {"conf.gltf", "buffer 0", "malformed data URI"});
  }
  doc["buffers"][0]["uri"] = good;
  doc["images"] = json::array({{{"uri", "data:image/png;base64,@@@@"}, {"name", "wood"}}});
  expect_error(load(doc.dump()), StatusCode::kInvalidArgument,
               {"image 0 'wood'", "malformed data URI"});
}

TEST(SceneConformance, ParserMessagesNameFileAndObject) {
  GltfBuilder b;
  b.add_node({{"mesh", b.add_mesh("q", {b.triangles(kQuadPositions, kQuadIndices)})}});
  b.doc["accessors"][1]["componentType"] = 5926;
  expect_error(load(b.gltf_embedded()), StatusCode::kInvalidArgument,
               {"conf.gltf", "accessor 1", "componentType 5926"});
  // A .glb with a broken magic is not "invalid JSON".
  std::string glb = GltfBuilder().glb();
  glb[0] = 'x';
  expect_error(load(glb, "bad.glb"), StatusCode::kInvalidArgument,
               {"bad.glb", "not a GLB", "bad magic"});
  // tinygltf rejects a wrongly typed property without a message.
  GltfBuilder c;
  c.add_node({{"mesh", c.add_mesh("q", {c.triangles(kQuadPositions, kQuadIndices)})}});
  json doc = json::parse(c.gltf_embedded());
  doc["nodes"] = json::array({1});
  auto r = load(doc.dump());
  ASSERT_FALSE(r.is_ok());
  const std::string msg = r.status().message();
  EXPECT_EQ(msg.find("conf.gltf"), 1u) << msg;
  EXPECT_GT(msg.size(), std::strlen("'conf.gltf': ") + 10) << msg;
}

// Brute force: every texel centre tested against every triangle with the
// top-left rule (the rasterizer's definition), counting centres covered by
// one mesh at least once and at least twice.
void brute_force(const Mesh& m, int res, size_t* covered, size_t* twice) {
  std::vector<int> count(static_cast<size_t>(res * res), 0);
  for (size_t t = 0; t < m.triangle_count(); ++t) {
    double p[3][2];
    for (int k = 0; k < 3; ++k) {
      const Vec2 uv = m.uv1[m.indices[3 * t + static_cast<size_t>(k)]];
      p[k][0] = static_cast<double>(uv.x) * res;
      p[k][1] = static_cast<double>(uv.y) * res;
    }
    const double area =
        (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]);
    if (area == 0) continue;
    if (area < 0) std::swap(p[1], p[2]);
    for (int y = 0; y < res; ++y) {
      for (int x = 0; x < res; ++x) {
        bool in = true;
        for (int k = 0; k < 3; ++k) {
          const double* a = p[k];
          const double* b = p[(k + 1) % 3];
          const double dx = b[0] - a[0], dy = b[1] - a[1];
          const double w = dx * (y + 0.5 - a[1]) - dy * (x + 0.5 - a[0]);
          const bool inclusive = dy < 0 || (dy == 0 && dx < 0);
          in = in && !(w < 0 || (w == 0 && !inclusive));
        }
        count[static_cast<size_t>(y * res + x)] += in;
      }
    }
  }
  *covered = *twice = 0;
  for (int c : count) {
    *covered += c > 0;
    *twice += c > 1;
  }
}

Scene uv_scene(std::vector<Vec2> uv) {
  Scene s;
  Mesh m;
  m.name = "uv";
  for (size_t i = 0; i < uv.size(); ++i) {
    m.positions.push_back({static_cast<float>(i), static_cast<float>(i * i % 7), 0});
    m.indices.push_back(static_cast<uint32_t>(i));
  }
  m.uv1 = std::move(uv);
  m.triangle_material.assign(m.indices.size() / 3, 0);
  s.meshes.push_back(std::move(m));
  return s;
}

TEST(SceneConformance, UvCoverageMatchesBruteForce) {
  constexpr int kRes = 24;
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> lattice(-2, 2 * kRes + 2);
  std::uniform_real_distribution<float> any(-0.1f, 1.1f);
  for (int round = 0; round < 20; ++round) {
    std::vector<Vec2> uv;
    for (int t = 0; t < 3 * 12; ++t) {
      // Half the vertices on the half-texel lattice, so that many centres
      // lie exactly on edges (shared and not).
      if (round % 2 == 0) {
        uv.push_back({lattice(rng) * 0.5f / kRes, lattice(rng) * 0.5f / kRes});
      } else {
        uv.push_back({any(rng), any(rng)});
      }
    }
    // A quad split along its diagonal: the shared edge runs through centres.
    for (Vec2 v : {Vec2{0.5f / kRes, 0.5f / kRes}, Vec2{8.5f / kRes, 0.5f / kRes},
                   Vec2{8.5f / kRes, 8.5f / kRes}, Vec2{0.5f / kRes, 0.5f / kRes},
                   Vec2{8.5f / kRes, 8.5f / kRes}, Vec2{0.5f / kRes, 8.5f / kRes}})
      uv.push_back(v);
    const Scene s = uv_scene(uv);
    size_t covered = 0, twice = 0;
    brute_force(s.meshes[0], kRes, &covered, &twice);
    const SceneStats st = compute_stats(s, kRes);
    EXPECT_EQ(st.lightmap_overlap_texels, twice) << "round " << round;
    EXPECT_NEAR(st.lightmap_coverage * kRes * kRes, static_cast<double>(covered), 1e-9)
        << "round " << round;
    const auto overlaps = find_uv_overlaps(s, kRes);
    EXPECT_EQ(overlaps.empty() ? 0u : overlaps[0].texels, twice) << "round " << round;
  }
  // The split quad alone: its diagonal is shared, nothing overlaps.
  const Scene quad = uv_scene(
      {{0.1f, 0.1f}, {0.6f, 0.1f}, {0.6f, 0.6f}, {0.1f, 0.1f}, {0.6f, 0.6f}, {0.1f, 0.6f}});
  EXPECT_TRUE(find_uv_overlaps(quad, 64).empty());
}

TEST(SceneConformance, UvCoverageOfRandomUvTrianglesIsLinear) {
  // 200k here to keep the test short (1M took 4.7 s on 2 loaded cores).
  constexpr size_t kTriangles = 200'000;
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<Vec2> uv(3 * kTriangles);
  for (Vec2& v : uv) v = {u(rng), u(rng)};
  const Scene s = uv_scene(std::move(uv));
  const auto t0 = std::chrono::steady_clock::now();
  const auto overlaps = find_uv_overlaps(s);
  const double seconds = seconds_since(t0);
  ASSERT_EQ(overlaps.size(), 1u);
  EXPECT_GT(overlaps[0].texels, 512u * 512u / 2);
  // Texel-by-texel rasterization took about 40 s for these (200 s for 1M);
  // the time is printed, not asserted (no test asserts on wall-clock time).
  std::printf("find_uv_overlaps: %zu random UV triangles in %.2f s\n", kTriangles, seconds);
}

TEST(SceneConformance, OverlappingLightmapUvsAreAnImportWarning) {
  GltfBuilder b;
  // Two meshes: "clean" with a quad, "folded" whose two triangles share UVs.
  const int clean = b.add_mesh("clean", {b.triangles(kQuadPositions, kQuadIndices)});
  json folded = b.triangles(kQuadPositions, kQuadIndices);
  folded["attributes"]["TEXCOORD_1"] =
      b.add_floats({0.1f, 0.1f, 0.9f, 0.1f, 0.9f, 0.9f, 0.9f, 0.1f}, "VEC2");
  // (vertex 3's UV is vertex 1's: triangle 0 2 3 lies over triangle 0 1 2)
  const int bad = b.add_mesh("folded", {folded});
  b.add_node({{"mesh", clean}});
  b.add_node({{"mesh", bad}});
  b.add_node({{"mesh", bad}});
  auto r = load(b.gltf_embedded());
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  const auto overlaps = find_uv_overlaps(*r);
  ASSERT_EQ(overlaps.size(), 1u);
  EXPECT_EQ(r->meshes[static_cast<size_t>(overlaps[0].mesh)].name, "folded");
  EXPECT_GT(overlaps[0].texels, 1000u);
  size_t n = 0;
  for (const auto& w : r->import_stats.warnings) n += w.find("TEXCOORD_1") != std::string::npos;
  EXPECT_EQ(n, 1u);
  EXPECT_TRUE(has_warning(*r, "mesh 'folded' (mesh[1]): TEXCOORD_1 (lightmap UVs) overlaps"));
}

}  // namespace
}  // namespace luxel::scene
