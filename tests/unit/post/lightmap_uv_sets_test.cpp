// Which TEXCOORD set the written-back lightmap UVs go to
// (post/lightmapped_gltf.h): never a set the file has or a material reads,
// indices kept contiguous, the set recorded (extras.lightmapTexCoord) and read
// back by the importer, a later write-back reusing its own set, and the
// written file baking to the same bits with --uv existing, textures still
// sampled through their own sets.
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "../scene/gltf_builder.h"
#include "bake/bake.h"
#include "output/manifest.h"
#include "post/bake_outputs.h"
#include "post/lightmapped_gltf.h"
#include "scene/gltf_import.h"
#include "support/device_context.h"

namespace luxel {
namespace {

using test::glb_json;
using test::read_all;

using nlohmann::json;
using test::GltfBuilder;

bool same(Vec2 a, Vec2 b) {
  return a.x == b.x && a.y == b.y;
}

// A unit cube with hard edges (24 vertices). Each face maps the whole unit
// square in TEXCOORD_0 and, turned a quarter, in TEXCOORD_1, so both sets
// overlap themselves and --uv auto generates lightmap UVs.
json cube(GltfBuilder& b, bool uv0, bool uv1, int material) {
  std::vector<float> pos, nrm, t0, t1;
  std::vector<uint32_t> idx;
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = -1; side <= 1; side += 2) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      const uint32_t base = static_cast<uint32_t>(pos.size() / 3);
      const float corners[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      for (const auto& c : corners) {
        float p[3], n[3] = {0, 0, 0};
        p[axis] = 0.5f * static_cast<float>(side);
        p[u] = c[0] - 0.5f;
        p[v] = c[1] - 0.5f;
        n[axis] = static_cast<float>(side);
        pos.insert(pos.end(), p, p + 3);
        nrm.insert(nrm.end(), n, n + 3);
        t0.insert(t0.end(), {c[0], c[1]});
        t1.insert(t1.end(), {c[1], 1 - c[0]});
      }
      if (side > 0)
        idx.insert(idx.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
      else
        idx.insert(idx.end(), {base, base + 2, base + 1, base, base + 3, base + 2});
    }
  }
  json prim;
  prim["attributes"]["POSITION"] = b.add_floats(pos, "VEC3");
  prim["attributes"]["NORMAL"] = b.add_floats(nrm, "VEC3");
  if (uv0) prim["attributes"]["TEXCOORD_0"] = b.add_floats(t0, "VEC2");
  if (uv1) prim["attributes"]["TEXCOORD_1"] = b.add_floats(t1, "VEC2");
  prim["indices"] = b.add_indices(idx, test::kUShort);
  prim["material"] = material;
  return prim;
}

// "logo": a cube with TEXCOORD_0 and TEXCOORD_1 whose emissive texture (four
// colours) is sampled through texCoord 1, as in Khronos' MultiUVTest;
// "plain": a cube with no UV set at all, as in Khronos' Box.
std::string two_cubes_glb() {
  GltfBuilder b;
  const std::vector<uint8_t> quadrants = {255, 0, 0,   255, 0,   255, 0,   255,
                                          0,   0, 255, 255, 255, 255, 255, 255};
  const std::string png = test::encode_png(2, 2, 4, quadrants);
  b.doc["images"] = {
      {{"bufferView", b.add_view(png.data(), png.size())}, {"mimeType", "image/png"}}};
  b.doc["samplers"] = {{{"magFilter", 9728}, {"minFilter", 9728}}};
  b.doc["textures"] = {{{"source", 0}, {"sampler", 0}}};
  b.add_material({{"name", "logo"},
                  {"pbrMetallicRoughness", {{"metallicFactor", 0.0}}},
                  {"emissiveFactor", {1, 1, 1}},
                  {"emissiveTexture", {{"index", 0}, {"texCoord", 1}}}});
  b.add_material({{"name", "plain"}, {"pbrMetallicRoughness", {{"metallicFactor", 0.0}}}});
  b.add_node({{"name", "logo"}, {"mesh", b.add_mesh("logo", {cube(b, true, true, 0)})}});
  b.add_node({{"name", "plain"},
              {"mesh", b.add_mesh("plain", {cube(b, false, false, 1)})},
              {"translation", {2, 0, 0}}});
  return b.glb();
}

class LightmapUvSetsTest : public testing::DeviceTest<> {
 protected:
  static pipeline::BakeSettings settings(pipeline::UvMode mode) {
    pipeline::BakeSettings s;
    s.atlas.resolution = 64;
    s.samples_per_texel = 4;
    s.max_bounces = 2;
    s.paths_per_iteration = 1u << 14;
    s.lights.sky.kind = pipeline::SkySettings::Kind::kConstant;
    s.uv = mode;
    return s;
  }
};

TEST_F(LightmapUvSetsTest, NoSetIsOverwrittenAndTheIndicesStayContiguous) {
  test::TempDir dir;
  const std::string source = dir.write("cubes.glb", two_cubes_glb());
  auto scene = scene::import_gltf_file(source);
  ASSERT_TRUE(scene) << scene.status().to_string();
  const scene::Mesh& logo_in = scene.value().meshes[0];
  auto first = pipeline::bake(scene.value(), settings(pipeline::UvMode::kAuto), *ctx_);
  ASSERT_TRUE(first) << first.status().to_string();
  ASSERT_TRUE(first.value().uv_layout) << "overlapping TEXCOORD_1 must be regenerated";
  auto written =
      pipeline::write_bake_outputs(dir.path() + "/out", scene.value(),
                                   settings(pipeline::UvMode::kAuto), first.value(), "", source);
  ASSERT_TRUE(written) << written.status().to_string();

  // In the file: the logo keeps TEXCOORD_0 and TEXCOORD_1 and gets its
  // lightmap in TEXCOORD_2; the plain cube gets a zero TEXCOORD_0 and its
  // lightmap in TEXCOORD_1. Both record the index.
  const json out = glb_json(read_all(written.value().lightmapped_glb));
  const json& logo = out["meshes"][0]["primitives"][0];
  const json& plain = out["meshes"][1]["primitives"][0];
  for (const char* set : {"TEXCOORD_0", "TEXCOORD_1", "TEXCOORD_2"})
    EXPECT_TRUE(logo["attributes"].contains(set)) << set;
  EXPECT_FALSE(logo["attributes"].contains("TEXCOORD_3"));
  EXPECT_EQ(logo["extras"]["lightmapTexCoord"], 2);
  EXPECT_TRUE(plain["attributes"].contains("TEXCOORD_0"));
  EXPECT_TRUE(plain["attributes"].contains("TEXCOORD_1"));
  EXPECT_FALSE(plain["attributes"].contains("TEXCOORD_2"));
  EXPECT_EQ(plain["extras"]["lightmapTexCoord"], 1);
  // The manifest says where the lightmap is.
  auto manifest = output::read_manifest(written.value().manifest_json);
  ASSERT_TRUE(manifest) << manifest.status().to_string();
  EXPECT_EQ(manifest.value().uv_sets.at("TEXCOORD_1"), 1u);
  EXPECT_EQ(manifest.value().uv_sets.at("TEXCOORD_2"), 1u);
  EXPECT_EQ(manifest.value().uv_set, "per primitive (extras.lightmapTexCoord)");

  // Read back by the importer: the lightmap from the recorded sets, the
  // material sets as in the input (each written vertex is an input vertex
  // or a seam copy of one).
  auto again = scene::import_gltf_file(written.value().lightmapped_glb);
  ASSERT_TRUE(again) << again.status().to_string();
  const scene::Mesh& logo_out = again.value().meshes[0];
  const auto& origin = first.value().uv_layout->meshes[0].vertex_origin;
  ASSERT_EQ(logo_out.positions.size(), origin.size());
  for (size_t v = 0; v < origin.size(); ++v) {
    EXPECT_TRUE(same(logo_out.uv0[v], logo_in.uv0[origin[v]])) << v;
    EXPECT_TRUE(same(logo_out.material_uvs(1)[v], logo_in.uv1[origin[v]])) << v;
    EXPECT_TRUE(same(logo_out.uv1[v], first.value().uv_layout->meshes[0].uv1[v])) << v;
  }
  for (const auto& m : again.value().meshes) EXPECT_TRUE(m.has_lightmap_uvs) << m.name;

  // The same bits with --uv existing: the emissive texture is still sampled
  // through the file's TEXCOORD_1 (reading it through the lightmap set would
  // move the four colours and change the bits).
  auto second = pipeline::bake(again.value(), settings(pipeline::UvMode::kExisting), *ctx_);
  ASSERT_TRUE(second) << second.status().to_string();
  ASSERT_EQ(second.value().irradiance.size(), first.value().irradiance.size());
  EXPECT_EQ(0, std::memcmp(second.value().irradiance.data(), first.value().irradiance.data(),
                           first.value().irradiance.size() * sizeof(float)));

  // A second write-back (UVs generated again) replaces its own set and adds
  // none.
  auto regen = pipeline::bake(again.value(), settings(pipeline::UvMode::kGenerate), *ctx_);
  ASSERT_TRUE(regen) << regen.status().to_string();
  pipeline::WritebackReport report;
  auto twice = pipeline::lightmapped_glb_bytes(read_all(written.value().lightmapped_glb), "",
                                               again.value(), regen.value(), &report);
  ASSERT_TRUE(twice) << twice.status().to_string();
  const json out2 = glb_json(twice.value());
  EXPECT_EQ(out2["meshes"][0]["primitives"][0]["attributes"].size(), logo["attributes"].size());
  EXPECT_EQ(out2["meshes"][0]["primitives"][0]["extras"]["lightmapTexCoord"], 2);
  EXPECT_EQ(out2["meshes"][1]["primitives"][0]["attributes"].size(), plain["attributes"].size());
  EXPECT_EQ(out2["meshes"][1]["primitives"][0]["extras"]["lightmapTexCoord"], 1);
  EXPECT_EQ(report.filler_sets, 0u);
}

// A material that samples texCoord 1 on a primitive without TEXCOORD_1
// keeps that index free: the lightmap goes to TEXCOORD_2, the zero sets
// below fill the gap.
TEST_F(LightmapUvSetsTest, AnIndexAMaterialReadsIsLeftFreeEvenWhenAbsent) {
  GltfBuilder b;
  const std::string png = test::encode_png(1, 1, 4, {255, 255, 255, 255});
  b.doc["images"] = {
      {{"bufferView", b.add_view(png.data(), png.size())}, {"mimeType", "image/png"}}};
  b.doc["textures"] = {{{"source", 0}}};
  b.add_material({{"name", "occlusion_on_1"},
                  {"pbrMetallicRoughness", {{"metallicFactor", 0.0}}},
                  {"occlusionTexture", {{"index", 0}, {"texCoord", 1}}}});
  b.add_node({{"name", "c"}, {"mesh", b.add_mesh("c", {cube(b, true, false, 0)})}});
  test::TempDir dir;
  const std::string source = dir.write("c.glb", b.glb());
  auto scene = scene::import_gltf_file(source);
  ASSERT_TRUE(scene) << scene.status().to_string();
  auto baked = pipeline::bake(scene.value(), settings(pipeline::UvMode::kAuto), *ctx_);
  ASSERT_TRUE(baked) << baked.status().to_string();
  pipeline::WritebackReport report;
  auto glb =
      pipeline::lightmapped_glb_bytes(read_all(source), "", scene.value(), baked.value(), &report);
  ASSERT_TRUE(glb) << glb.status().to_string();
  const json prim = glb_json(glb.value())["meshes"][0]["primitives"][0];
  EXPECT_EQ(prim["extras"]["lightmapTexCoord"], 2);
  EXPECT_TRUE(prim["attributes"].contains("TEXCOORD_1"));
  EXPECT_EQ(report.filler_sets, 1u);
  EXPECT_EQ(report.texcoord_primitives.at(2), 1u);
  ASSERT_FALSE(report.warnings.empty());
  EXPECT_NE(report.warnings[0].find("TEXCOORD_2"), std::string::npos) << report.warnings[0];
}

}  // namespace
}  // namespace luxel
