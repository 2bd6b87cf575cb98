// Generated lightmap UVs written back into the scene file
// (post/lightmapped_gltf.h) and read back: everything else survives,
// the layout is honoured exactly (extras.lightmapScaleOffset, atlas mode
// "placed"), and baking the written file with --uv existing gives the same
// lightmap bit for bit.
#include "post/lightmapped_gltf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "../scene/gltf_builder.h"
#include "bake/bake.h"
#include "device/context.h"
#include "post/bake_outputs.h"
#include "scene/gltf_import.h"
#include "support/device_context.h"

namespace luxel {
namespace {

using test::glb_json;
using test::read_all;

using nlohmann::json;
using test::GltfBuilder;

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

class LightmappedGltfTest : public testing::DeviceTest<> {
 protected:
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
};

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
  auto written =
      pipeline::write_bake_outputs(dir.path() + "/out", scene.value(),
                                   settings(pipeline::UvMode::kAuto), first.value(), "", source);
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

// The client dictates the layout through the API (BakeSettings::
// node_placements) instead of the file's extras: the same placement gives
// the same bits; overlap is refused naming both nodes; a node that is not
// baked or an instance index it lacks is named.
TEST_F(LightmappedGltfTest, PlacementsThroughTheApiAreHonouredExactly) {
  test::TempDir dir;
  const std::string source = dir.write("boxes.glb", scene_glb());
  auto scene = scene::import_gltf_file(source);
  ASSERT_TRUE(scene);
  auto first = pipeline::bake(scene.value(), settings(pipeline::UvMode::kGenerate), *ctx_);
  ASSERT_TRUE(first) << first.status().to_string();
  auto written = pipeline::write_bake_outputs(dir.path() + "/out", scene.value(),
                                              settings(pipeline::UvMode::kGenerate), first.value(),
                                              "", source);
  ASSERT_TRUE(written) << written.status().to_string();
  auto placed = scene::import_gltf_file(written.value().lightmapped_glb);
  ASSERT_TRUE(placed);
  // The file's extras move into the settings; the scene keeps none.
  scene::Scene bare = placed.value();
  pipeline::BakeSettings s = settings(pipeline::UvMode::kAuto);
  for (scene::Instance& inst : bare.instances) {
    ASSERT_TRUE(inst.has_lightmap_scale_offset);
    pipeline::NodePlacement np;
    np.node = inst.node_index;
    for (int k = 0; k < 4; ++k) np.scale_offset[k] = inst.lightmap_scale_offset[k];
    s.node_placements.push_back(np);
    inst.has_lightmap_scale_offset = false;
  }
  ASSERT_TRUE(pipeline::validate_settings(s).is_ok());
  auto second = pipeline::bake(bare, s, *ctx_);
  ASSERT_TRUE(second) << second.status().to_string();
  EXPECT_EQ(second.value().atlas.mode, atlas::AtlasMode::kPlaced);
  ASSERT_EQ(second.value().irradiance.size(), first.value().irradiance.size());
  EXPECT_EQ(0, std::memcmp(second.value().irradiance.data(), first.value().irradiance.data(),
                           first.value().irradiance.size() * sizeof(float)));

  // 'large' (node 1) onto 'small' (node 0).
  pipeline::BakeSettings overlap = s;
  overlap.node_placements[1].scale_offset[2] = overlap.node_placements[0].scale_offset[2];
  overlap.node_placements[1].scale_offset[3] = overlap.node_placements[0].scale_offset[3];
  auto r = pipeline::bake(bare, overlap, *ctx_);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find("'small'"), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find("'large'"), std::string::npos) << r.status().message();

  pipeline::BakeSettings unknown = s;
  unknown.node_placements[2].node = 17;
  auto u = pipeline::bake(bare, unknown, *ctx_);
  ASSERT_FALSE(u);
  EXPECT_NE(u.status().message().find("settings.placements[2].node: node 17"), std::string::npos)
      << u.status().message();
  pipeline::BakeSettings element = s;
  element.node_placements[0].element = 3;
  auto e = pipeline::bake(bare, element, *ctx_);
  ASSERT_FALSE(e);
  EXPECT_NE(e.status().message().find("node 0 has no instance 3"), std::string::npos)
      << e.status().message();
  // Placement maps the file's TEXCOORD_1: it cannot go with generated UVs.
  pipeline::BakeSettings generate = s;
  generate.uv = pipeline::UvMode::kGenerate;
  EXPECT_FALSE(pipeline::bake(bare, generate, *ctx_));
  // Settings-level rules name the entry.
  pipeline::BakeSettings twice = s;
  twice.node_placements.push_back(twice.node_placements[0]);
  EXPECT_NE(
      pipeline::validate_settings(twice).message().find("placements[3]: node 0 is placed twice"),
      std::string::npos)
      << pipeline::validate_settings(twice).message();
  pipeline::BakeSettings zero = s;
  zero.node_placements[0].scale_offset[1] = 0;
  EXPECT_NE(pipeline::validate_settings(zero).message().find("placements[0].scale_offset"),
            std::string::npos);
}

// Past max_resolution at the requested density the generated layout goes on
// several pages (lightmap arrays). Checked independently of the packer: the
// written-back file's TEXCOORD_1 mapped by each node's lightmapScaleOffset
// onto its lightmapIndex page, with texel centres tested triangle by
// triangle: every instance lies inside its page and no texel centre of a
// page is inside triangles of two instances. Outputs are per page, and the
// written-back file bakes to the same bits.
TEST_F(LightmappedGltfTest, MultiPageLayoutPutsEveryTexelOnOnePage) {
  GltfBuilder b;
  b.add_material({{"name", "wall"}, {"pbrMetallicRoughness", {{"metallicFactor", 0.0}}}});
  constexpr int kBoxes = 6;
  for (int i = 0; i < kBoxes; ++i)
    b.add_node({{"name", "box" + std::to_string(i)},
                {"mesh", b.add_mesh("box" + std::to_string(i), {box_primitive(b, 1.0f)})},
                {"translation", {3.0 * i, 0, 0}}});
  test::TempDir dir;
  const std::string source = dir.write("pages.glb", b.glb());
  auto scene = scene::import_gltf_file(source);
  ASSERT_TRUE(scene) << scene.status().to_string();
  // 64^2 pages; 6 texels per unit makes each box's six 12 x 12 faces, with
  // padding, take about a third of a page: two boxes a page, three pages.
  pipeline::BakeSettings s = settings(pipeline::UvMode::kAuto);
  s.atlas.resolution = 0;
  s.atlas.texel_density = 6;
  s.atlas.max_resolution = 64;
  auto first = pipeline::bake(scene.value(), s, *ctx_);
  ASSERT_TRUE(first) << first.status().to_string();
  const atlas::Atlas& at = first.value().atlas;
  ASSERT_EQ(at.pages, 3);
  EXPECT_EQ(at.width, 64);
  EXPECT_EQ(at.height, 3 * 64);
  ASSERT_TRUE(first.value().uv_layout);
  EXPECT_EQ(first.value().uv_layout->report.pages, 3);
  EXPECT_EQ(first.value().uv_layout->report.overlapping_texels, 0u);

  auto written = pipeline::write_bake_outputs(dir.path() + "/out", scene.value(), s, first.value(),
                                              "", source);
  ASSERT_TRUE(written) << written.status().to_string();
  for (int p = 0; p < 3; ++p)
    for (const char* stem : {"irradiance_", "samples_", "rel_error_", "preview_"}) {
      const std::string f = dir.path() + "/out/" + stem + std::to_string(p) +
                            (std::string(stem) == "preview_" ? ".png" : ".exr");
      EXPECT_FALSE(read_all(f).empty()) << f;
    }
  const json manifest = json::parse(read_all(written.value().manifest_json));
  EXPECT_EQ(manifest["pages"], 3);
  EXPECT_EQ(manifest["height"], 64);

  // Independent check on the written file.
  const json out = glb_json(read_all(written.value().lightmapped_glb));
  auto again = scene::import_gltf_file(written.value().lightmapped_glb);
  ASSERT_TRUE(again) << again.status().to_string();
  const scene::Scene& sc = again.value();
  std::vector<std::vector<int>> owner(3, std::vector<int>(64 * 64, -1));
  std::vector<int> instances_on_page(3, 0);
  for (size_t i = 0; i < sc.instances.size(); ++i) {
    const json& extras = out["nodes"][static_cast<size_t>(sc.instances[i].node_index)]["extras"];
    const int page = extras["lightmapIndex"].get<int>();
    ASSERT_GE(page, 0);
    ASSERT_LT(page, 3);
    ++instances_on_page[static_cast<size_t>(page)];
    double so[4];
    for (int k = 0; k < 4; ++k) so[k] = extras["lightmapScaleOffset"][static_cast<size_t>(k)];
    const scene::Mesh& m = sc.meshes[static_cast<size_t>(sc.instances[i].mesh)];
    for (size_t t = 0; t < m.triangle_count(); ++t) {
      double x[3], y[3];
      for (int j = 0; j < 3; ++j) {
        const Vec2 uv = m.uv1[m.indices[3 * t + static_cast<size_t>(j)]];
        x[j] = (uv.x * so[0] + so[2]) * 64;
        y[j] = (uv.y * so[1] + so[3]) * 64;
        ASSERT_GE(x[j], -1e-3) << "instance " << i;
        ASSERT_LE(x[j], 64 + 1e-3) << "instance " << i;
        ASSERT_GE(y[j], -1e-3) << "instance " << i;
        ASSERT_LE(y[j], 64 + 1e-3) << "instance " << i;
      }
      const double area = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
      for (int ty = 0; ty < 64; ++ty)
        for (int tx = 0; tx < 64; ++tx) {
          const double px = tx + 0.5, py = ty + 0.5;
          bool inside = true;
          for (int j = 0; j < 3; ++j) {
            const int k = (j + 1) % 3;
            const double w = (x[k] - x[j]) * (py - y[j]) - (y[k] - y[j]) * (px - x[j]);
            inside = inside && (area > 0 ? w > 0 : w < 0);
          }
          if (!inside) continue;
          int& o = owner[static_cast<size_t>(page)][static_cast<size_t>(ty * 64 + tx)];
          EXPECT_TRUE(o < 0 || o == static_cast<int>(i))
              << "page " << page << " texel " << tx << "," << ty << ": instances " << o << " and "
              << i;
          o = static_cast<int>(i);
        }
    }
  }
  for (int p = 0; p < 3; ++p) EXPECT_GT(instances_on_page[static_cast<size_t>(p)], 0) << p;

  pipeline::BakeSettings existing = s;
  existing.uv = pipeline::UvMode::kExisting;
  auto second = pipeline::bake(sc, existing, *ctx_);
  ASSERT_TRUE(second) << second.status().to_string();
  EXPECT_EQ(second.value().atlas.pages, 3);
  ASSERT_EQ(second.value().irradiance.size(), first.value().irradiance.size());
  EXPECT_EQ(0, std::memcmp(second.value().irradiance.data(), first.value().irradiance.data(),
                           first.value().irradiance.size() * sizeof(float)))
      << "the written-back pages must bake to the same bits";
}

}  // namespace
}  // namespace luxel
