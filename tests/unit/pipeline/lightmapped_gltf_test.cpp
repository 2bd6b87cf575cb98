// Generated lightmap UVs written back into the scene file
// (pipeline/lightmapped_gltf.h) and read back: everything else survives,
// the layout is honoured exactly (extras.lightmapScaleOffset, atlas mode
// "placed"), and baking the written file with --uv existing gives the same
// lightmap bit for bit.
#include "pipeline/lightmapped_gltf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "../scene/gltf_builder.h"
#include "device/context.h"
#include "pipeline/bake.h"
#include "pipeline/bake_outputs.h"
#include "scene/gltf_import.h"

namespace luxel {
namespace {

using nlohmann::json;
using test::GltfBuilder;

std::string read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The JSON chunk of a GLB, parsed independently of the writer.
json glb_json(const std::string& bytes) {
  uint32_t length = 0;
  std::memcpy(&length, bytes.data() + 12, 4);
  return json::parse(bytes.substr(20, length));
}

// A box with hard edges (24 vertices, per-face normals), no TEXCOORD_1,
// with TEXCOORD_0; `scale` sets its size.
json box_primitive(GltfBuilder& b, float size) {
  std::vector<float> pos, nrm, uv0;
  std::vector<uint32_t> idx;
  const float n[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (int f = 0; f < 6; ++f) {
    const float nx = n[f][0], ny = n[f][1], nz = n[f][2];
    // Two tangent axes u, v with cross(u, v) = n.
    float u[3] = {ny != 0 ? 1.0f : 0.0f, 0, ny != 0 ? 0.0f : 1.0f};
    if (nz != 0) u[0] = 1, u[2] = 0;
    float v[3] = {ny * u[2] - nz * u[1], nz * u[0] - nx * u[2], nx * u[1] - ny * u[0]};
    const uint32_t base = static_cast<uint32_t>(pos.size() / 3);
    const float corners[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    for (const auto& c : corners) {
      for (int k = 0; k < 3; ++k) pos.push_back(size * (n[f][k] + c[0] * u[k] + c[1] * v[k]));
      nrm.insert(nrm.end(), {nx, ny, nz});
      uv0.insert(uv0.end(), {0.5f + 0.5f * c[0], 0.5f + 0.5f * c[1]});
    }
    idx.insert(idx.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
  }
  json prim;
  prim["attributes"]["POSITION"] = b.add_floats(pos, "VEC3");
  prim["attributes"]["NORMAL"] = b.add_floats(nrm, "VEC3");
  prim["attributes"]["TEXCOORD_0"] = b.add_floats(uv0, "VEC2");
  prim["indices"] = b.add_indices(idx, test::kUShort);
  prim["material"] = 0;
  return prim;
}

class LightmappedGltfTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    auto ctx = device::Context::create();
    ASSERT_TRUE(ctx) << ctx.status().to_string();
    ctx_ = std::move(ctx.value()).release();
  }
  static void TearDownTestSuite() { delete ctx_; }

  static pipeline::BakeSettings settings(pipeline::UvMode mode) {
    pipeline::BakeSettings s;
    s.atlas.resolution = 64;
    s.samples_per_texel = 8;
    s.max_bounces = 2;
    s.paths_per_iteration = 1u << 14;
    s.lights.sky.kind = pipeline::SkySettings::Kind::kConstant;
    s.uv = mode;
    return s;
  }

  // Two boxes of different sizes from one mesh (instanced) and a third from
  // its own mesh; a material with an unknown extension and extras.
  static std::string scene_glb() {
    GltfBuilder b;
    b.add_material({{"name", "wall"},
                    {"pbrMetallicRoughness",
                     {{"baseColorFactor", {0.8, 0.8, 0.8, 1}}, {"metallicFactor", 0.0}}},
                    {"extras", {{"keep", "me"}}},
                    {"extensions", {{"EXT_luxel_unknown", {{"answer", 42}}}}}});
    const int shared = b.add_mesh("shared_box", {box_primitive(b, 0.5f)});
    const int own = b.add_mesh("own_box", {box_primitive(b, 1.0f)});
    b.add_node({{"name", "small"}, {"mesh", shared}, {"translation", {-3, 0, 0}}});
    b.add_node({{"name", "large"},
                {"mesh", shared},
                {"translation", {3, 0, 0}},
                {"scale", {2, 2, 2}},
                {"extras", {{"tag", 7}}}});
    b.add_node({{"name", "single"}, {"mesh", own}, {"translation", {0, 0, 4}}});
    b.doc["extensionsUsed"] = {"EXT_luxel_unknown"};
    return b.glb();
  }

  static device::Context* ctx_;
};
device::Context* LightmappedGltfTest::ctx_ = nullptr;

TEST_F(LightmappedGltfTest, RoundTripKeepsTheFileAndBakesTheSameBits) {
  test::TempDir dir;
  const std::string source = dir.write("boxes.glb", scene_glb());
  auto scene = scene::import_gltf_file(source);
  ASSERT_TRUE(scene) << scene.status().to_string();
  for (const auto& m : scene.value().meshes) EXPECT_FALSE(m.has_lightmap_uvs);

  auto first = pipeline::bake(scene.value(), settings(pipeline::UvMode::kAuto), *ctx_);
  ASSERT_TRUE(first) << first.status().to_string();
  ASSERT_TRUE(first.value().uv_layout);
  EXPECT_EQ(first.value().atlas.mode, atlas::AtlasMode::kGenerated);
  EXPECT_NE(first.value().uv_layout->reason.find("TEXCOORD_1"), std::string::npos);

  auto written =
      pipeline::write_bake_outputs(dir.path() + "/out", scene.value(),
                                   settings(pipeline::UvMode::kAuto), first.value(), "", source);
  ASSERT_TRUE(written) << written.status().to_string();
  ASSERT_FALSE(written.value().lightmapped_glb.empty());
  EXPECT_NE(written.value().lightmapped_glb.find("boxes_lightmapped.glb"), std::string::npos);

  // Everything else survived: the material's extension and extras, node
  // extras, names; and every baked node has its scale/offset.
  const json in = glb_json(read_all(source));
  const json out = glb_json(read_all(written.value().lightmapped_glb));
  EXPECT_EQ(out["materials"], in["materials"]);
  EXPECT_EQ(out["extensionsUsed"], in["extensionsUsed"]);
  ASSERT_EQ(out["nodes"].size(), in["nodes"].size());
  for (size_t n = 0; n < in["nodes"].size(); ++n) {
    json stripped = out["nodes"][n];
    ASSERT_TRUE(stripped["extras"].contains("lightmapScaleOffset")) << n;
    stripped["extras"].erase("lightmapScaleOffset");
    if (stripped["extras"].empty()) stripped.erase("extras");
    EXPECT_EQ(stripped, in["nodes"][n]) << "node " << n;
  }
  const auto& placements = first.value().atlas.placements;
  for (size_t i = 0; i < placements.size(); ++i) {
    const auto& inst = scene.value().instances[i];
    const json so =
        out["nodes"][static_cast<size_t>(inst.node_index)]["extras"]["lightmapScaleOffset"];
    EXPECT_EQ(so[0].get<float>(), placements[i].scale[0]);
    EXPECT_EQ(so[1].get<float>(), placements[i].scale[1]);
    EXPECT_EQ(so[2].get<float>(), placements[i].offset[0]);
    EXPECT_EQ(so[3].get<float>(), placements[i].offset[1]);
  }
  // The two instances of the shared mesh sit in different places at sizes
  // in proportion to their world sizes (x2).
  const int small = 0, large = 1;
  EXPECT_NEAR(placements[large].scale[0] / placements[small].scale[0], 2.0, 1e-4);
  EXPECT_NE(placements[large].offset[0], placements[small].offset[0]);

  // Read back: TEXCOORD_1 everywhere, and the file's placement is honoured.
  auto again = scene::import_gltf_file(written.value().lightmapped_glb);
  ASSERT_TRUE(again) << again.status().to_string();
  for (const auto& m : again.value().meshes) EXPECT_TRUE(m.has_lightmap_uvs) << m.name;
  auto second = pipeline::bake(again.value(), settings(pipeline::UvMode::kExisting), *ctx_);
  ASSERT_TRUE(second) << second.status().to_string();
  EXPECT_EQ(second.value().atlas.mode, atlas::AtlasMode::kPlaced);
  EXPECT_FALSE(second.value().uv_layout);
  ASSERT_EQ(second.value().irradiance.size(), first.value().irradiance.size());
  EXPECT_EQ(second.value().covered_texels, first.value().covered_texels);
  EXPECT_EQ(0, std::memcmp(second.value().irradiance.data(), first.value().irradiance.data(),
                           first.value().irradiance.size() * sizeof(float)))
      << "the written-back scene must bake to the same bits";
}

TEST_F(LightmappedGltfTest, ExistingModeRefusesAMeshWithoutLightmapUvs) {
  test::TempDir dir;
  auto scene = scene::import_gltf_file(dir.write("boxes.glb", scene_glb()));
  ASSERT_TRUE(scene);
  auto r = pipeline::bake(scene.value(), settings(pipeline::UvMode::kExisting), *ctx_);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find("TEXCOORD_1"), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find("shared_box"), std::string::npos) << r.status().message();
}

TEST_F(LightmappedGltfTest, OverlappingPlacementsAreRefusedNamingBothNodes) {
  test::TempDir dir;
  auto scene = scene::import_gltf_file(dir.write("boxes.glb", scene_glb()));
  ASSERT_TRUE(scene);
  auto first = pipeline::bake(scene.value(), settings(pipeline::UvMode::kGenerate), *ctx_);
  ASSERT_TRUE(first) << first.status().to_string();
  auto written = pipeline::write_bake_outputs(dir.path() + "/out", scene.value(),
                                              settings(pipeline::UvMode::kGenerate), first.value(),
                                              "", dir.path() + "/boxes.glb");
  ASSERT_TRUE(written) << written.status().to_string();
  auto placed = scene::import_gltf_file(written.value().lightmapped_glb);
  ASSERT_TRUE(placed);
  // Move 'large' onto 'small': the same offset.
  scene::Scene s = placed.value();
  s.instances[1].lightmap_scale_offset[2] = s.instances[0].lightmap_scale_offset[2];
  s.instances[1].lightmap_scale_offset[3] = s.instances[0].lightmap_scale_offset[3];
  auto r = pipeline::bake(s, settings(pipeline::UvMode::kExisting), *ctx_);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find("'small'"), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find("'large'"), std::string::npos) << r.status().message();
  // Some nodes with a placement and some without is an error too.
  s = placed.value();
  s.instances[2].has_lightmap_scale_offset = false;
  auto partial = pipeline::bake(s, settings(pipeline::UvMode::kExisting), *ctx_);
  ASSERT_FALSE(partial);
  EXPECT_NE(partial.status().message().find("'single'"), std::string::npos)
      << partial.status().message();
}

// A triangle strip (mode 5) comes back as the triangle list the importer
// read (mode 4) with its generated UVs, and bakes to the same bits.
TEST_F(LightmappedGltfTest, StripsAreWrittenBackAsTriangleLists) {
  GltfBuilder b;
  b.add_material({{"name", "floor"}, {"pbrMetallicRoughness", {{"metallicFactor", 0.0}}}});
  // A folded ribbon: two rows of 6 vertices, the second row bent upwards.
  std::vector<float> pos, nrm;
  for (int i = 0; i < 6; ++i) {
    const float x = static_cast<float>(i);
    pos.insert(pos.end(), {x, 0, 0, x, i < 3 ? 0.0f : 0.5f, i < 3 ? 1.0f : 1.5f});
    nrm.insert(nrm.end(), {0, 1, 0, 0, 1, 0});
  }
  std::vector<uint32_t> strip;
  for (uint32_t i = 0; i < 6; ++i) strip.insert(strip.end(), {2 * i, 2 * i + 1});
  json prim;
  prim["attributes"]["POSITION"] = b.add_floats(pos, "VEC3");
  prim["attributes"]["NORMAL"] = b.add_floats(nrm, "VEC3");
  prim["indices"] = b.add_indices(strip, test::kUShort);
  prim["mode"] = 5;
  prim["material"] = 0;
  b.add_node({{"name", "ribbon"}, {"mesh", b.add_mesh("ribbon", {prim})}});
  test::TempDir dir;
  const std::string source = dir.write("ribbon.glb", b.glb());
  auto scene = scene::import_gltf_file(source);
  ASSERT_TRUE(scene) << scene.status().to_string();
  ASSERT_EQ(scene.value().meshes[0].triangle_count(), 10u);
  auto first = pipeline::bake(scene.value(), settings(pipeline::UvMode::kAuto), *ctx_);
  ASSERT_TRUE(first) << first.status().to_string();
  auto written = pipeline::write_bake_outputs(dir.path() + "/out", scene.value(),
                                              settings(pipeline::UvMode::kAuto), first.value(), "",
                                              source);
  ASSERT_TRUE(written) << written.status().to_string();
  const json out = glb_json(read_all(written.value().lightmapped_glb));
  EXPECT_EQ(out["meshes"][0]["primitives"][0]["mode"], 4);
  auto again = scene::import_gltf_file(written.value().lightmapped_glb);
  ASSERT_TRUE(again) << again.status().to_string();
  ASSERT_EQ(again.value().meshes[0].triangle_count(), 10u);
  auto second = pipeline::bake(again.value(), settings(pipeline::UvMode::kExisting), *ctx_);
  ASSERT_TRUE(second) << second.status().to_string();
  ASSERT_EQ(second.value().irradiance.size(), first.value().irradiance.size());
  EXPECT_EQ(0, std::memcmp(second.value().irradiance.data(), first.value().irradiance.data(),
                           first.value().irradiance.size() * sizeof(float)));
}

}  // namespace
}  // namespace luxel
