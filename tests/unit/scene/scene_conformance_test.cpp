// Valid glTF 2.0 features the importer once refused or dropped, and invalid
// files it once accepted or reported without naming the file and object.
// Each case is a small document built in memory.
#include <gtest/gtest.h>

#include <cstring>

#include "gltf_builder.h"
#include "scene/gltf_import.h"

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

}  // namespace
}  // namespace luxel::scene
