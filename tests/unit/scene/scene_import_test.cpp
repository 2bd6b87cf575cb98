// Crafted glTF files (built in memory by GltfBuilder): good ones checked
// numerically, bad ones checked for their status code and for a message that
// names the thing at fault.
// Over 500 lines: one test per import rule (containers, accessors, sparse data,
// materials, lights, limits), so a rule and its refusals read side by side over
// one GltfBuilder.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>

#include "gltf_builder.h"
#include "scene/gltf_import.h"
#include "scene/scene_stats.h"

namespace luxel::scene {
namespace {

using test::GltfBuilder;
using test::json;
using test::kQuadIndices;
using test::kQuadPositions;

Result<Scene> load(const std::string& bytes, const ImportOptions& options = {}) {
  return import_gltf_memory(bytes, "", "test.gltf", options);
}

// Asserts an error with `code` whose message contains every needle.
void expect_error(const Result<Scene>& r, StatusCode code,
                  std::initializer_list<const char*> needles) {
  ASSERT_FALSE(r.is_ok());
  EXPECT_EQ(r.status().code(), code) << r.status().to_string();
  for (const char* n : needles)
    EXPECT_NE(r.status().message().find(n), std::string::npos)
        << "'" << n << "' not in: " << r.status().message();
}

void expect_near(Vec3 a, Vec3 b, float eps = 1e-5f) {
  EXPECT_NEAR(a.x, b.x, eps);
  EXPECT_NEAR(a.y, b.y, eps);
  EXPECT_NEAR(a.z, b.z, eps);
}

GltfBuilder quad_scene(int index_type = test::kUInt) {
  GltfBuilder b;
  const int mesh = b.add_mesh("quad", {b.triangles(kQuadPositions, kQuadIndices, index_type)});
  b.add_node({{"mesh", mesh}, {"name", "n"}});
  return b;
}

TEST(SceneImport, IndexedU8U16U32AndNonIndexed) {
  for (int type : {test::kUByte, test::kUShort, test::kUInt}) {
    auto r = load(quad_scene(type).gltf_embedded());
    ASSERT_TRUE(r.is_ok()) << r.status().to_string();
    ASSERT_EQ(r->meshes.size(), 1u);
    EXPECT_EQ(r->meshes[0].triangle_count(), 2u);
    EXPECT_EQ(r->meshes[0].indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
  }
  GltfBuilder b;
  const std::vector<float> soup = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 0, 0, 1, 1, 0, 0, 1, 0};
  b.add_node({{"mesh", b.add_mesh("soup", {b.triangles(soup)})}});
  auto r = load(b.gltf_embedded());
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  EXPECT_EQ(r->meshes[0].triangle_count(), 2u);
  EXPECT_NEAR(r->meshes[0].uv1[2].x, 0.1f, 1e-7f);
}

TEST(SceneImport, ExternalBinAndGlb) {
  test::TempDir dir;
  GltfBuilder b = quad_scene();
  dir.write("scene.bin", std::string(b.bin.begin(), b.bin.end()));
  const std::string gltf = dir.write("scene.gltf", b.gltf_external("scene.bin"));
  auto r = import_gltf_file(gltf);
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  EXPECT_EQ(r->meshes[0].triangle_count(), 2u);

  const std::string glb = b.glb();
  auto g = import_gltf_memory(glb, "", "x.glb");
  ASSERT_TRUE(g.is_ok()) << g.status().to_string();
  EXPECT_EQ(g->meshes[0].positions.size(), 4u);
  auto gf = import_gltf_file(dir.write("scene.glb", glb));
  ASSERT_TRUE(gf.is_ok()) << gf.status().to_string();
}

TEST(SceneImport, HierarchyTrsMatrixAndInstancing) {
  GltfBuilder b;
  const int mesh = b.add_mesh("quad", {b.triangles(kQuadPositions, kQuadIndices)});
  // child: matrix translating by (0, 1, 0); parent: T(10,0,0) R(90 deg about Y) S(2)
  json matrix = json::array({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 1, 0, 1});
  const int child = b.add_child_node({{"name", "child"}, {"mesh", mesh}, {"matrix", matrix}});
  const double h = std::sqrt(0.5);
  b.add_node({{"name", "parent"},
              {"children", {child}},
              {"translation", {10, 0, 0}},
              {"rotation", {0, h, 0, h}},
              {"scale", {2, 2, 2}}});
  b.add_node({{"name", "other"}, {"mesh", mesh}, {"translation", {0, 0, -5}}});
  auto r = load(b.gltf_embedded());
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  ASSERT_EQ(r->meshes.size(), 1u);
  ASSERT_EQ(r->instances.size(), 2u);
  EXPECT_EQ(r->instances[0].name, "child");
  EXPECT_EQ(r->instances[0].mesh, r->instances[1].mesh);
  // Vertex (1,0,0): child -> (1,1,0); scale 2 -> (2,2,0); Ry(90): x -> -z -> (0,2,-2); +T ->
  // (10,2,-2).
  expect_near(transform_point(r->instances[0].object_to_world, r->meshes[0].positions[1]),
              {10, 2, -2});
  expect_near(transform_point(r->instances[1].object_to_world, r->meshes[0].positions[1]),
              {1, 0, -5});
  const SceneStats s = compute_stats(*r, 64);
  EXPECT_EQ(s.mesh_triangles, 2u);
  EXPECT_EQ(s.world_triangles, 4u);
}

TEST(SceneImport, GeneratedNormals) {
  auto r = load(quad_scene().gltf_embedded());
  ASSERT_TRUE(r.is_ok());
  EXPECT_TRUE(r->meshes[0].generated_normals);
  for (const Vec3& n : r->meshes[0].normals) expect_near(n, {0, 0, 1});
}

TEST(SceneImport, DegenerateAndZeroAreaTrianglesDropped) {
  GltfBuilder b;
  const std::vector<float> pos = {0, 0, 0, 1, 0, 0, 1, 1, 0, 2, 0, 0};
  // 1 good, 1 repeated index, 1 collinear (0, 1, 3 on the x axis)
  const int mesh = b.add_mesh("m", {b.triangles(pos, {0, 1, 2, 0, 0, 1, 0, 1, 3})});
  b.add_node({{"mesh", mesh}});
  auto r = load(b.gltf_embedded());
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  EXPECT_EQ(r->meshes[0].triangle_count(), 1u);
  EXPECT_EQ(r->import_stats.degenerate_triangles_dropped, 2u);
}

TEST(SceneImport, EmptySceneIsValid) {
  GltfBuilder b;
  auto r = load(b.gltf_embedded());
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  EXPECT_EQ(compute_stats(*r).world_triangles, 0u);
  EXPECT_EQ(r->materials.size(), 1u);
}

TEST(SceneImport, NonTrianglePrimitiveSkippedWithWarning) {
  GltfBuilder b;
  json lines = b.triangles(kQuadPositions, {0, 1});
  lines["mode"] = 1;
  b.add_node({{"mesh", b.add_mesh("wire", {b.triangles(kQuadPositions, kQuadIndices), lines})}});
  auto r = load(b.gltf_embedded());
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  EXPECT_EQ(r->import_stats.skipped_primitives, 1u);
  ASSERT_EQ(r->import_stats.warnings.size(), 1u);
  EXPECT_NE(r->import_stats.warnings[0].find("mesh 'wire' (mesh[0]) primitive 1"),
            std::string::npos);
}

TEST(SceneImport, QuantizedTexcoordsAndSparse) {
  GltfBuilder b;
  json prim = b.triangles(kQuadPositions, kQuadIndices);
  const std::vector<uint16_t> uv = {0, 0, 65535, 0, 65535, 65535, 0, 32768};
  prim["attributes"]["TEXCOORD_0"] =
      b.add_accessor(b.add_view(uv.data(), 16), test::kUShort, 4, "VEC2", 0, true);
  // Sparse POSITION: base quad, vertex 2 replaced by (2, 2, 0).
  const uint8_t idx[4] = {2, 0, 0, 0};
  const float val[3] = {2, 2, 0};
  const int base = prim["attributes"]["POSITION"];
  b.doc["accessors"][base]["sparse"] = {
      {"count", 1},
      {"indices", {{"bufferView", b.add_view(idx, 4)}, {"componentType", test::kUByte}}},
      {"values", {{"bufferView", b.add_view(val, 12)}}}};
  b.add_node({{"mesh", b.add_mesh("q", {prim})}});
  auto r = load(b.gltf_embedded());
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  EXPECT_FLOAT_EQ(r->meshes[0].uv0[1].x, 1.0f);
  EXPECT_NEAR(r->meshes[0].uv0[3].y, 32768.0f / 65535.0f, 1e-7f);
  expect_near(r->meshes[0].positions[2], {2, 2, 0});
}

TEST(SceneImport, MaterialsAllFieldsAndTextures) {
  GltfBuilder b;
  // 2x1 RGBA image: texel 0 = (128, 64, 255, 128), texel 1 = (0, 0, 0, 255)
  const std::string png = test::encode_png(2, 1, 4, {128, 64, 255, 128, 0, 0, 0, 255});
  b.doc["images"] =
      json::array({{{"uri", "data:image/png;base64," + test::base64(png)}, {"name", "tex"}}});
  b.doc["textures"] = json::array({{{"source", 0}}});
  const int mat = b.add_material(
      {{"name", "full"},
       {"pbrMetallicRoughness",
        {{"baseColorFactor", {0.5, 0.25, 1, 1}},
         {"baseColorTexture", {{"index", 0}, {"texCoord", 1}}},
         {"metallicFactor", 0.3},
         {"roughnessFactor", 0.7},
         {"metallicRoughnessTexture", {{"index", 0}}}}},
       {"emissiveFactor", {1, 0.5, 0}},
       {"emissiveTexture", {{"index", 0}}},
       {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 17}}}}},
       {"doubleSided", true},
       {"alphaMode", "MASK"},
       {"alphaCutoff", 0.25}});
  json prim = b.triangles(kQuadPositions, kQuadIndices);
  prim["material"] = mat;
  json plain = b.triangles(kQuadPositions, kQuadIndices);  // no material: glTF default
  b.add_node({{"mesh", b.add_mesh("m", {prim, plain})}});
  auto r = load(b.gltf_embedded());
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  ASSERT_EQ(r->materials.size(), 2u);
  const Material& m = r->materials[0];
  EXPECT_EQ(m.name, "full");
  EXPECT_FLOAT_EQ(m.base_color_factor.y, 0.25f);
  EXPECT_FLOAT_EQ(m.metallic_factor, 0.3f);
  EXPECT_FLOAT_EQ(m.roughness_factor, 0.7f);
  EXPECT_FLOAT_EQ(m.emissive_factor.y, 0.5f);
  EXPECT_FLOAT_EQ(m.emissive_strength, 17.0f);
  EXPECT_TRUE(m.double_sided);
  EXPECT_EQ(m.alpha_mode, AlphaMode::kMask);
  EXPECT_FLOAT_EQ(m.alpha_cutoff, 0.25f);
  EXPECT_EQ(m.base_color_texture.texcoord, 1);
  EXPECT_EQ(r->materials[1].name, "default");
  EXPECT_EQ(r->materials[1].alpha_mode, AlphaMode::kOpaque);
  EXPECT_EQ(r->meshes[0].triangle_material, (std::vector<int32_t>{0, 0, 1, 1}));

  // One image used as sRGB (base colour, emissive) and linear (metal/rough): two textures.
  ASSERT_EQ(r->textures.size(), 2u);
  EXPECT_EQ(m.base_color_texture.texture, m.emissive_texture.texture);
  const Texture& srgb = r->textures[static_cast<size_t>(m.base_color_texture.texture)];
  const Texture& lin = r->textures[static_cast<size_t>(m.metallic_roughness_texture.texture)];
  EXPECT_EQ(srgb.source_space, ColorSpace::kSRGB);
  EXPECT_EQ(lin.source_space, ColorSpace::kLinear);
  // 8-bit images keep the file's codes (4 bytes per texel); linear() decodes.
  ASSERT_EQ(srgb.format, TexelFormat::kRGBA8);
  ASSERT_EQ(srgb.rgba8.size(), 8u);
  EXPECT_EQ(srgb.rgba8[0], 128);
  EXPECT_EQ(srgb.pixel_bytes(), 8u);
  const double c = 128.0 / 255.0;
  EXPECT_NEAR(srgb.linear(0).x, std::pow((c + 0.055) / 1.055, 2.4), 1e-6);  // 0.2158605
  EXPECT_NEAR(srgb.linear(0).y, std::pow((64.0 / 255 + 0.055) / 1.055, 2.4), 1e-6);
  EXPECT_NEAR(srgb.linear(0).z, 1.0, 1e-6);
  EXPECT_NEAR(srgb.linear(0).w, c, 1e-6);  // alpha stays linear
  EXPECT_NEAR(lin.linear(0).x, c, 1e-6);
  EXPECT_NEAR(srgb.linear(1).x, 0.0, 1e-7);
  EXPECT_NEAR(srgb.linear(1).w, 1.0, 1e-7);

  const SceneStats s = compute_stats(*r, 64);
  EXPECT_EQ(s.alpha_masked_triangles, 2u);
  EXPECT_EQ(s.emissive_triangles, 2u);
  // area 1 x pi x mean(1, 0.5, 0) x 17 x mean of the sRGB texture's RGB
  double tex_mean = 0;
  for (size_t i : {0u, 1u})
    tex_mean += double(srgb.linear(i).x) + srgb.linear(i).y + srgb.linear(i).z;
  tex_mean /= 6;
  EXPECT_NEAR(s.emissive_power, M_PI * 0.5 * 17 * tex_mean, 1e-4);
  EXPECT_NE(format_stats(s).find("emissive"), std::string::npos);
}

// Material inputs the bake does not apply are named in the warnings (which
// `luxel inspect`, the upload reply and the manifest carry), never dropped
// silently; a file that uses only supported inputs gets none.
TEST(SceneImport, UnsupportedMaterialInputsAreNamed) {
  GltfBuilder b;
  const std::string png = test::encode_png(1, 1, 4, {255, 255, 255, 255});
  b.doc["images"] = json::array({{{"uri", "data:image/png;base64," + test::base64(png)}}});
  b.doc["samplers"] = json::array({{{"wrapS", 33071}, {"wrapT", 10497}}});  // CLAMP_TO_EDGE
  b.doc["textures"] = json::array({{{"source", 0}}, {{"source", 0}, {"sampler", 0}}});
  b.doc["extensionsUsed"] = json::array({"KHR_texture_transform", "KHR_materials_clearcoat",
                                         "KHR_materials_ior", "KHR_materials_emissive_strength"});
  const int mat = b.add_material(
      {{"name", "painted"},
       {"pbrMetallicRoughness",
        {{"baseColorTexture",
          {{"index", 0}, {"extensions", {{"KHR_texture_transform", {{"scale", {2, 2}}}}}}}},
         {"metallicRoughnessTexture", {{"index", 1}}}}},
       {"emissiveTexture", {{"index", 0}, {"texCoord", 1}}},
       {"normalTexture", {{"index", 0}}},
       {"extensions",
        {{"KHR_materials_clearcoat", {{"clearcoatFactor", 1}}},
         {"KHR_materials_ior", {{"ior", 1.7}}},
         {"KHR_materials_specular",
          {{"specularFactor", 0.5},
           {"specularColorFactor", {20, 1, 0.5}},
           {"specularTexture", {{"index", 0}}}}},
         {"KHR_materials_emissive_strength", {{"emissiveStrength", 2}}}}}});
  json prim = b.triangles(kQuadPositions, kQuadIndices);
  prim["material"] = mat;
  b.add_node({{"mesh", b.add_mesh("m", {prim})}});
  auto r = load(b.gltf_embedded());
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  const auto& w = r->import_stats.warnings;
  auto has = [&](std::initializer_list<const char*> needles) {
    for (const std::string& line : w) {
      bool all = true;
      for (const char* n : needles) all = all && line.find(n) != std::string::npos;
      if (all) return true;
    }
    return false;
  };
  EXPECT_FALSE(has({"KHR_texture_transform"})) << "it is supported";
  EXPECT_TRUE(has({"extension KHR_materials_clearcoat", "not supported"}));
  EXPECT_FALSE(has({"KHR_materials_emissive_strength"})) << "it is supported";
  EXPECT_FALSE(has({"KHR_materials_ior"})) << "it is supported";
  // ior 1.7: f0 = (0.7 / 2.7)^2.
  EXPECT_FLOAT_EQ(r->materials[0].ior, 1.7f);
  EXPECT_NEAR(r->materials[0].dielectric_f0(), (0.7 / 2.7) * (0.7 / 2.7), 1e-7);
  // Texture transforms, wrap modes and texCoord 1 are applied, not warned about.
  const Material& pm = r->materials[0];
  EXPECT_TRUE(pm.base_color_texture.has_transform);
  EXPECT_FLOAT_EQ(pm.base_color_texture.scale.x, 2.0f);
  EXPECT_FALSE(pm.metallic_roughness_texture.has_transform);
  EXPECT_EQ(pm.metallic_roughness_texture.wrap_s, WrapMode::kClampToEdge);
  EXPECT_EQ(pm.metallic_roughness_texture.wrap_t, WrapMode::kRepeat);
  EXPECT_EQ(pm.emissive_texture.texcoord, 1);
  EXPECT_FALSE(has({"sampler"}));
  EXPECT_FALSE(has({"texCoord"}));
  // The normal map is applied; what is named is that this quad lacks the UV
  // set it reads (its tangents cannot follow the map).
  EXPECT_FALSE(has({"normalTexture is not supported"}));
  EXPECT_TRUE(has({"material 'painted'", "normalTexture on TEXCOORD_0", "lacks"}));
  EXPECT_GE(pm.normal_texture.texture, 0);
  EXPECT_TRUE(has({"material 'painted'", "material extension KHR_materials_clearcoat"}));
  // KHR_materials_specular: F0 = min(F0(ior) color, 1) specular, F90 = specular;
  // its texture is named.
  const double f0 = (0.7 / 2.7) * (0.7 / 2.7);
  const Vec3 sf0 = pm.dielectric_specular_f0();
  EXPECT_NEAR(sf0.x, 0.5, 1e-7) << "20 f0 = 1.34 clamps to 1";
  EXPECT_NEAR(sf0.y, f0 * 0.5, 1e-7);
  EXPECT_NEAR(sf0.z, f0 * 0.25, 1e-7);
  EXPECT_FLOAT_EQ(pm.dielectric_specular_f90(), 0.5f);
  EXPECT_TRUE(has({"material 'painted'", "KHR_materials_specular specularTexture"}));
  EXPECT_FALSE(has({"material extension KHR_materials_specular"}));
  EXPECT_EQ(w.size(), 4u) << "one line per input";

  // The plain quad of the other tests: nothing to report, the default ior.
  auto plain = load(quad_scene().gltf_embedded());
  ASSERT_TRUE(plain.is_ok());
  EXPECT_TRUE(plain->import_stats.warnings.empty());
  EXPECT_FLOAT_EQ(plain->materials[0].dielectric_f0(), 0.04f);
}

// A quad primitive (kQuadPositions, normal +z) with TEXCOORD_0 = uv(x, y) at
// its corners and material `material`.
json quad_with_uv0(GltfBuilder& b, const std::function<std::array<float, 2>(float, float)>& uv,
                   int material) {
  json prim = b.triangles(kQuadPositions, kQuadIndices);
  std::vector<float> uvs;
  for (size_t i = 0; i < kQuadPositions.size(); i += 3) {
    const auto c = uv(kQuadPositions[i], kQuadPositions[i + 1]);
    uvs.insert(uvs.end(), {c[0], c[1]});
  }
  prim["attributes"]["TEXCOORD_0"] = b.add_floats(uvs, "VEC2");
  prim["material"] = material;
  return prim;
}

int add_normal_map_material(GltfBuilder& b, json normal_texture) {
  const std::string png = test::encode_png(1, 1, 4, {128, 128, 255, 255});
  b.doc["images"] = json::array({{{"uri", "data:image/png;base64," + test::base64(png)}}});
  b.doc["textures"] = json::array({{{"source", 0}}});
  return b.add_material({{"name", "bumpy"}, {"normalTexture", std::move(normal_texture)}});
}

// normalTextureInfo: index, texCoord, scale and KHR_texture_transform land in
// the material's slot (linear, like every data texture), without warnings.
TEST(SceneImport, NormalTextureSlot) {
  GltfBuilder b;
  b.doc["extensionsUsed"] = json::array({"KHR_texture_transform"});
  const int mat = add_normal_map_material(
      b,
      {{"index", 0},
       {"texCoord", 1},
       {"scale", 0.25},
       {"extensions",
        {{"KHR_texture_transform", {{"offset", {0.5, 0}}, {"rotation", 0.5}, {"texCoord", 0}}}}}});
  const int plain = b.add_material({{"name", "plain"}});
  b.add_node({{"mesh", b.add_mesh("bumpy", {quad_with_uv0(
                                               b,
                                               [](float x, float y) {
                                                 return std::array<float, 2>{x, 1 - y};
                                               },
                                               mat)})}});
  b.add_node({{"mesh", b.add_mesh("flat", {quad_with_uv0(
                                              b,
                                              [](float x, float y) {
                                                return std::array<float, 2>{x, y};
                                              },
                                              plain)})}});
  auto r = load(b.gltf_embedded());
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  EXPECT_TRUE(r->import_stats.warnings.empty()) << r->import_stats.warnings.front();
  const Material& m = r->materials[static_cast<size_t>(mat)];
  ASSERT_GE(m.normal_texture.texture, 0);
  EXPECT_EQ(r->textures[static_cast<size_t>(m.normal_texture.texture)].source_space,
            ColorSpace::kLinear);
  EXPECT_FLOAT_EQ(m.normal_scale, 0.25f);
  EXPECT_EQ(m.normal_texture.texcoord, 0) << "KHR_texture_transform's texCoord overrides";
  EXPECT_TRUE(m.normal_texture.has_transform);
  EXPECT_FLOAT_EQ(m.normal_texture.offset.x, 0.5f);
  EXPECT_FLOAT_EQ(m.normal_texture.rotation, 0.5f);
  EXPECT_FLOAT_EQ(r->materials[static_cast<size_t>(plain)].normal_scale, 1.0f);
  EXPECT_LT(r->materials[static_cast<size_t>(plain)].normal_texture.texture, 0);
  // Tangents only where a normal map needs them.
  ASSERT_EQ(r->meshes.size(), 2u);
  EXPECT_EQ(r->meshes[0].tangents.size(), 4u);
  EXPECT_TRUE(r->meshes[1].tangents.empty());
}

// TANGENT is read (normalised, w reduced to its sign) when the primitive has it.
TEST(SceneImport, NormalMapReadsTangentAttribute) {
  GltfBuilder b;
  const int mat = add_normal_map_material(b, {{"index", 0}});
  json prim = quad_with_uv0(
      b,
      [](float x, float y) {
        return std::array<float, 2>{x, 1 - y};
      },
      mat);
  prim["attributes"]["TANGENT"] =
      b.add_floats({0, 2, 0, -1, 0, 2, 0, -1, 0, 2, 0, -1, 0, 2, 0, -1}, "VEC4");
  b.add_node({{"mesh", b.add_mesh("m", {prim})}});
  auto r = load(b.gltf_embedded());
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  ASSERT_EQ(r->meshes[0].tangents.size(), 4u);
  for (const Vec4& t : r->meshes[0].tangents) {
    EXPECT_FLOAT_EQ(t.x, 0);
    EXPECT_FLOAT_EQ(t.y, 1);
    EXPECT_FLOAT_EQ(t.z, 0);
    EXPECT_FLOAT_EQ(t.w, -1);
  }
}

// Without TANGENT, tangents are generated from the normal map's UV set: unit,
// orthogonal to the normal, along +u; w = +1 for a mapping that shows the
// image upright (glTF v runs down the image, the map's +Y up) and -1 for a
// mirrored one.
TEST(SceneImport, NormalMapGeneratesTangentsAlongPlusU) {
  struct Case {
    const char* what;
    std::function<std::array<float, 2>(float, float)> uv;
    Vec3 plus_u;
    float w;
  } cases[] = {
      {"upright",
       [](float x, float y) {
         return std::array<float, 2>{x, 1 - y};
       },
       {1, 0, 0},
       1},
      {"u along +y",
       [](float x, float y) {
         return std::array<float, 2>{y, x};
       },
       {0, 1, 0},
       1},
      {"mirrored",
       [](float x, float y) {
         return std::array<float, 2>{1 - x, 1 - y};
       },
       {-1, 0, 0},
       -1},
      {"scaled, rotated 45 degrees",
       [](float x, float y) {
         return std::array<float, 2>{3 * (x + y), 3 * (x - y)};
       },
       {0.70710678f, 0.70710678f, 0},
       1},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    GltfBuilder b;
    const int mat = add_normal_map_material(b, {{"index", 0}});
    b.add_node({{"mesh", b.add_mesh("m", {quad_with_uv0(b, c.uv, mat)})}});
    auto r = load(b.gltf_embedded());
    ASSERT_TRUE(r.is_ok()) << r.status().to_string();
    const Mesh& mesh = r->meshes[0];
    ASSERT_EQ(mesh.tangents.size(), mesh.positions.size());
    for (size_t v = 0; v < mesh.tangents.size(); ++v) {
      const Vec4 t = mesh.tangents[v];
      const Vec3 xyz{t.x, t.y, t.z};
      EXPECT_NEAR(length(xyz), 1.0f, 1e-6f);
      EXPECT_NEAR(dot(xyz, mesh.normals[v]), 0.0f, 1e-6f);
      expect_near(xyz, c.plus_u, 1e-6f);
      EXPECT_EQ(t.w, c.w);
    }
  }
}

TEST(SceneImportErrors, IorOutsideTheExtensionsRange) {
  for (double ior : {0.5, -1.0}) {
    GltfBuilder b;
    const int mat = b.add_material(
        {{"name", "glass"}, {"extensions", {{"KHR_materials_ior", {{"ior", ior}}}}}});
    json prim = b.triangles(kQuadPositions, kQuadIndices);
    prim["material"] = mat;
    b.add_node({{"mesh", b.add_mesh("m", {prim})}});
    expect_error(load(b.gltf_embedded()), StatusCode::kInvalidArgument,
                 {"material 'glass'", "KHR_materials_ior ior", "is not 0 or in [1, 1e6]"});
  }
  // ior 0 is allowed: f0 = 1.
  GltfBuilder b;
  const int mat =
      b.add_material({{"name", "mirror"}, {"extensions", {{"KHR_materials_ior", {{"ior", 0}}}}}});
  json prim = b.triangles(kQuadPositions, kQuadIndices);
  prim["material"] = mat;
  b.add_node({{"mesh", b.add_mesh("m", {prim})}});
  auto r = load(b.gltf_embedded());
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  EXPECT_EQ(r->materials[0].dielectric_f0(), 1.0f);
}

TEST(SceneImport, SixteenBitGreyImageExpandsToRgba) {
  GltfBuilder b;
  const std::string png = test::encode_png16_gray(2, 1, {0x8000, 0xFFFF});
  b.doc["images"] = json::array(
      {{{"bufferView", b.add_view(png.data(), png.size())}, {"mimeType", "image/png"}}});
  b.doc["textures"] = json::array({{{"source", 0}}});
  b.add_material(
      {{"pbrMetallicRoughness",
        {{"baseColorTexture", {{"index", 0}}}, {"metallicRoughnessTexture", {{"index", 0}}}}}});
  json prim = b.triangles(kQuadPositions, kQuadIndices);
  prim["material"] = 0;
  b.add_node({{"mesh", b.add_mesh("m", {prim})}});
  auto r = load(b.glb());
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  ASSERT_EQ(r->textures.size(), 2u);
  const Texture& srgb = r->textures[0];
  const Texture& lin = r->textures[1];
  ASSERT_EQ(srgb.width, 2);
  const double v = 32768.0 / 65535.0;
  // 16-bit images are linear halves: within the half unit roundoff (2^-11 relative).
  ASSERT_EQ(srgb.format, TexelFormat::kRGBA16F);
  EXPECT_EQ(srgb.pixel_bytes(), 2u * 4 * 2);
  const double e = std::pow((v + 0.055) / 1.055, 2.4);
  const float s0[3] = {srgb.linear(0).x, srgb.linear(0).y, srgb.linear(0).z};
  const float l0[3] = {lin.linear(0).x, lin.linear(0).y, lin.linear(0).z};
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(s0[c], e, e * 0x1p-11);
    EXPECT_NEAR(l0[c], v, v * 0x1p-11);
  }
  EXPECT_NE(double(l0[0]), v) << "v is not a half: the test would not see the conversion";
  EXPECT_FLOAT_EQ(srgb.linear(0).w, 1.0f);  // grey has no alpha: opaque
  EXPECT_FLOAT_EQ(srgb.linear(1).x, 1.0f);

  ImportOptions no_decode;
  no_decode.decode_textures = false;
  auto n = load(b.glb(), no_decode);
  ASSERT_TRUE(n.is_ok());
  EXPECT_EQ(n->textures[0].width, 2);
  EXPECT_FALSE(n->textures[0].has_pixels());
}

TEST(SceneImport, PunctualLights) {
  GltfBuilder b;
  b.doc["extensionsUsed"] = {"KHR_lights_punctual"};
  b.doc["extensions"]["KHR_lights_punctual"]["lights"] = json::array(
      {{{"type", "point"}, {"intensity", 100}, {"color", {1, 0.5, 0.25}}, {"name", "bulb"}},
       {{"type", "spot"},
        {"intensity", 50},
        {"spot", {{"innerConeAngle", 0.1}, {"outerConeAngle", 0.5}}}},
       {{"type", "directional"}, {"intensity", 3}}});
  auto light = [](int i) { return json{{"KHR_lights_punctual", {{"light", i}}}}; };
  b.add_node({{"translation", {1, 2, 3}}, {"extensions", light(0)}});
  const double h = std::sqrt(0.5);
  // Rotated -90 deg about X: -Z turns into -Y (points down).
  b.add_node({{"translation", {0, 5, 0}}, {"rotation", {-h, 0, 0, h}}, {"extensions", light(1)}});
  b.add_node({{"rotation", {0, h, 0, h}}, {"extensions", light(2)}});  // 90 deg about Y: -Z -> -X
  auto r = load(b.gltf_embedded());
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  ASSERT_EQ(r->lights.size(), 3u);
  EXPECT_EQ(r->lights[0].type, LightType::kPoint);
  EXPECT_EQ(r->lights[0].name, "bulb");
  expect_near(r->lights[0].position, {1, 2, 3});
  expect_near(r->lights[0].color, {1, 0.5f, 0.25f});
  EXPECT_FLOAT_EQ(r->lights[0].intensity, 100.0f);
  EXPECT_EQ(r->lights[1].type, LightType::kSpot);
  expect_near(r->lights[1].position, {0, 5, 0});
  expect_near(r->lights[1].direction, {0, -1, 0});
  EXPECT_FLOAT_EQ(r->lights[1].outer_cone_angle, 0.5f);
  EXPECT_EQ(r->lights[2].type, LightType::kDirectional);
  expect_near(r->lights[2].direction, {-1, 0, 0});
  const SceneStats s = compute_stats(*r);
  EXPECT_EQ(s.point_lights + s.spot_lights + s.directional_lights, 3u);
}

TEST(SceneImport, DeepHierarchyWithoutRecursion) {
  GltfBuilder b;
  const int mesh = b.add_mesh("q", {b.triangles(kQuadPositions, kQuadIndices)});
  const int depth = 20000;
  for (int i = 0; i < depth; ++i) {
    json n = {{"translation", {0, 0, 1}}};
    if (i + 1 < depth) n["children"] = {i + 1};
    if (i + 1 == depth) n["mesh"] = mesh;
    if (i == 0)
      b.add_node(n);
    else
      b.add_child_node(n);
  }
  auto r = load(b.gltf_embedded());
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  expect_near(transform_point(r->instances[0].object_to_world, {0, 0, 0}), {0, 0, depth});
}

// ---- bad files ----

TEST(SceneImportErrors, NaNPosition) {
  GltfBuilder b;
  std::vector<float> pos = kQuadPositions;
  pos[4] = std::numeric_limits<float>::quiet_NaN();
  b.add_node({{"mesh", b.add_mesh("floor", {b.triangles(pos, kQuadIndices)})}});
  expect_error(load(b.gltf_embedded()), StatusCode::kInvalidArgument,
               {"mesh 'floor' (mesh[0]) primitive 0", "accessor 0 (POSITION)", "NaN"});
}

TEST(SceneImportErrors, NaNNodeTransform) {
  GltfBuilder b = quad_scene();
  const int child = b.add_child_node({{"name", "far"}, {"translation", {1e300, 0, 0}}});
  b.doc["nodes"][0]["scale"] = {1e300, 1, 1};
  b.doc["nodes"][0]["children"] = {child};
  expect_error(load(b.gltf_embedded()), StatusCode::kInvalidArgument,
               {"node 'far' (node[1])", "overflow"});
  // A literal too large for a double is rejected by the JSON parser.
  std::string text = quad_scene().gltf_embedded();
  const std::string key = "\"name\":\"n\"";
  text.replace(text.find(key), key.size(), key + ",\"rotation\":[0,0,0,1e999]");
  expect_error(load(text), StatusCode::kInvalidArgument, {"1e999"});
}

TEST(SceneImportErrors, IndexOutOfRange) {
  GltfBuilder b;
  b.add_node({{"mesh", b.add_mesh("floor", {b.triangles(kQuadPositions, {0, 1, 7})})}});
  expect_error(load(b.gltf_embedded()), StatusCode::kInvalidArgument,
               {"mesh 'floor'", "(indices)", "index 7", "out of range"});
}

TEST(SceneImportErrors, StrideSmallerThanElement) {
  GltfBuilder b = quad_scene();
  b.doc["bufferViews"][0]["byteStride"] = 8;
  expect_error(load(b.gltf_embedded()), StatusCode::kInvalidArgument,
               {"mesh 'quad' (mesh[0]) primitive 0: accessor 0 (POSITION): byteStride 8 is smaller "
                "than the element "
                "size 12"});
}

TEST(SceneImportErrors, StrideOutsideTheSchemaRange) {
  // tinygltf reads byteStride 0 as "tightly packed"; the schema allows 4-252.
  for (const json& bad : {json(0), json(2), json(6), json(256), json(-12)}) {
    GltfBuilder b = quad_scene();
    b.doc["bufferViews"][0]["byteStride"] = bad;
    expect_error(load(b.gltf_embedded()), StatusCode::kInvalidArgument,
                 {"test.gltf", "accessor 0", "bufferView 0", "byteStride"});
  }
  // A view no accessor reads is named by itself.
  GltfBuilder b = quad_scene();
  const std::string unread = "bufferView " + std::to_string(b.doc["bufferViews"].size());
  b.doc["bufferViews"].push_back({{"buffer", 0}, {"byteLength", 4}, {"byteStride", 0}});
  expect_error(load(b.gltf_embedded()), StatusCode::kInvalidArgument,
               {"test.gltf", unread.c_str(), "byteStride 0"});
}

TEST(SceneImportErrors, NegativeMaterialIndex) {
  GltfBuilder b = quad_scene();
  b.doc["meshes"][0]["primitives"][0]["material"] = -5;
  expect_error(load(b.gltf_embedded()), StatusCode::kInvalidArgument,
               {"test.gltf", "mesh 'quad' (mesh[0]) primitive 0", "material -5"});
}

TEST(SceneImportErrors, StrideOverrunsView) {
  GltfBuilder b = quad_scene();
  b.doc["bufferViews"][0]["byteStride"] = 16;  // 3 * 16 + 12 = 60 > 48
  expect_error(load(b.gltf_embedded()), StatusCode::kInvalidArgument,
               {"accessor 0 (POSITION)", "overrun"});
}

TEST(SceneImportErrors, CountOverrunsView) {
  GltfBuilder b = quad_scene();
  b.doc["accessors"][0]["count"] = 5;
  expect_error(load(b.gltf_embedded()), StatusCode::kInvalidArgument,
               {"accessor 0 (POSITION)", "overrun"});
  b.doc["accessors"][0]["count"] = 0x7fffffffffffffffLL;  // overflows count * stride
  expect_error(load(b.gltf_embedded()), StatusCode::kResourceExhausted, {"accessor 0 (POSITION)"});
  ImportOptions unlimited;
  unlimited.max_accessor_elements = std::numeric_limits<uint64_t>::max();
  expect_error(load(b.gltf_embedded(), unlimited), StatusCode::kInvalidArgument,
               {"accessor 0 (POSITION)", "overrun"});
}

TEST(SceneImportErrors, ViewOverrunsBuffer) {
  GltfBuilder b = quad_scene();
  b.doc["bufferViews"][0]["byteOffset"] = 1000;
  expect_error(load(b.gltf_embedded()), StatusCode::kDataLoss,
               {"bufferView 0", "overruns buffer 0"});
}

TEST(SceneImportErrors, MissingBinAndImage) {
  test::TempDir dir;
  GltfBuilder b = quad_scene();
  const std::string path = dir.write("scene.gltf", b.gltf_external("missing.bin"));
  expect_error(import_gltf_file(path), StatusCode::kNotFound, {"buffer 0", "missing.bin"});
  expect_error(import_gltf_file(dir.path() + "/nothing.gltf"), StatusCode::kNotFound,
               {"nothing.gltf"});
  // An external buffer in a memory import without a base folder.
  expect_error(load(b.gltf_external("scene.bin")), StatusCode::kNotFound, {"scene.bin"});

  dir.write("scene.bin", std::string(b.bin.begin(), b.bin.end()));
  b.doc["images"] = json::array({{{"uri", "textures/wood.png"}}});
  b.doc["textures"] = json::array({{{"source", 0}}});
  b.add_material({{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}});
  const std::string p2 = dir.write("scene2.gltf", b.gltf_external("scene.bin"));
  expect_error(import_gltf_file(p2), StatusCode::kNotFound, {"image 0", "textures/wood.png"});
  // Escaping the scene folder is refused.
  b.doc["images"][0]["uri"] = "../secret.png";
  const std::string p3 = dir.write("scene3.gltf", b.gltf_external("scene.bin"));
  expect_error(import_gltf_file(p3), StatusCode::kInvalidArgument, {"../secret.png"});
}

TEST(SceneImportErrors, PercentEscapesInUris) {
  test::TempDir dir;
  GltfBuilder b = quad_scene();
  dir.write("my scene.bin", std::string(b.bin.begin(), b.bin.end()));
  // "%20" is a space (common/uri.h), so the file beside the .gltf is found.
  auto ok = import_gltf_file(dir.write("ok.gltf", b.gltf_external("my%20scene.bin")));
  ASSERT_TRUE(ok.is_ok()) << ok.status().to_string();
  // Malformed escapes are refused with the uri named, not read literally.
  for (const char* uri : {"my%2scene.bin", "my%zzscene.bin", "scene.bin%", "a.bin%00.txt"}) {
    const std::string path = dir.write("bad.gltf", b.gltf_external(uri));
    expect_error(import_gltf_file(path), StatusCode::kInvalidArgument, {"buffer 0", uri});
  }
}

TEST(SceneImportErrors, TruncatedBin) {
  test::TempDir dir;
  GltfBuilder b = quad_scene();
  dir.write("scene.bin", std::string(b.bin.begin(), b.bin.end() - 8));
  expect_error(import_gltf_file(dir.write("s.gltf", b.gltf_external("scene.bin"))),
               StatusCode::kDataLoss, {"buffer 0", "byteLength"});
}

TEST(SceneImportErrors, MissingLightmapUvs) {
  GltfBuilder b;
  b.add_node({{"mesh", b.add_mesh("wall", {b.triangles(kQuadPositions, kQuadIndices, test::kUInt,
                                                       false)})}});
  ImportOptions strict;
  strict.require_lightmap_uvs = true;
  expect_error(load(b.gltf_embedded(), strict), StatusCode::kInvalidArgument,
               {"TEXCOORD_1", "mesh 'wall'"});
  // By default the mesh loads and says it needs generated lightmap UVs.
  auto scene = load(b.gltf_embedded());
  ASSERT_TRUE(scene.is_ok()) << scene.status().message();
  EXPECT_FALSE(scene.value().meshes[0].has_lightmap_uvs);
  EXPECT_TRUE(load(quad_scene().gltf_embedded()).value().meshes[0].has_lightmap_uvs);
}

TEST(SceneImportErrors, NodeCycleAndSeveralParents) {
  GltfBuilder b = quad_scene();
  b.add_child_node({{"name", "a"}, {"children", {2}}});
  b.add_child_node({{"name", "b"}, {"children", {1}}});
  expect_error(load(b.gltf_embedded()), StatusCode::kInvalidArgument, {"cycle", "node '"});

  GltfBuilder c = quad_scene();
  c.add_node({{"name", "p1"}, {"children", {3}}});
  c.add_node({{"name", "p2"}, {"children", {3}}});
  c.add_child_node({{"name", "shared"}});
  expect_error(load(c.gltf_embedded()), StatusCode::kInvalidArgument,
               {"node 'shared' (node[3])", "several parents"});

  GltfBuilder d = quad_scene();
  d.doc["nodes"][0]["children"] = {0};
  expect_error(load(d.gltf_embedded()), StatusCode::kInvalidArgument, {"node 'n' (node[0])"});
}

TEST(SceneImportErrors, BadComponentType) {
  GltfBuilder b = quad_scene();
  // (unsigned shorts are valid positions under KHR_mesh_quantization)
  b.doc["accessors"][0]["componentType"] = test::kUInt;
  expect_error(load(b.gltf_embedded()), StatusCode::kInvalidArgument,
               {"accessor 0 (POSITION)", "componentType 5125", "UNSIGNED_INT"});
  GltfBuilder c = quad_scene();
  c.doc["accessors"][2]["componentType"] = test::kFloat;  // indices as float
  expect_error(load(c.gltf_embedded()), StatusCode::kInvalidArgument,
               {"(indices)", "componentType 5126"});
}

TEST(SceneImportErrors, TruncatedGlb) {
  const std::string glb = quad_scene().glb();
  for (size_t cut : {size_t{8}, size_t{40}, glb.size() - 4}) {
    expect_error(import_gltf_memory(glb.substr(0, cut), "", "t.glb"), StatusCode::kDataLoss,
                 {"t.glb", "truncated"});
  }
}

TEST(SceneImportErrors, MalformedJson) {
  expect_error(load("{\"asset\": "), StatusCode::kInvalidArgument, {"JSON"});
  expect_error(load(std::string(1000, '[')), StatusCode::kInvalidArgument, {"nested"});
}

TEST(SceneImportErrors, OversizedImageRejectedBeforeDecoding) {
  GltfBuilder b = quad_scene();
  const std::string png = test::encode_png(64, 64, 4, std::vector<uint8_t>(64 * 64 * 4, 7));
  b.doc["images"] = json::array({{{"uri", "data:image/png;base64," + test::base64(png)}}});
  b.doc["textures"] = json::array({{{"source", 0}}});
  b.add_material({{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}});
  ImportOptions small;
  small.max_image_side = 32;
  expect_error(load(b.gltf_embedded(), small), StatusCode::kResourceExhausted,
               {"image 0", "64 x 64"});
  EXPECT_TRUE(load(b.gltf_embedded()).is_ok());
}

// stb_image refuses to even describe an image it would not decode (over 2^30
// bytes), so such a header is measured by the importer itself.
TEST(SceneImportErrors, HugeImageHeaderIsTooLargeNotUnknown) {
  std::string png = test::encode_png(1, 1, 4, std::vector<uint8_t>(4, 7));
  for (size_t i = 16; i < 24; ++i) png[i] = static_cast<char>(i % 4 < 2 ? 0x00 : 0xFF);
  // Baseline JPEG, SOF0 claiming 65535 x 65535 with three components.
  const std::string jpeg(
      "\xFF\xD8\xFF\xE0\x00\x04\x00\x00\xFF\xC0\x00\x11\x08\xFF\xFF\xFF\xFF"
      "\x03\x01\x22\x00\x02\x11\x01\x03\x11\x01",
      27);
  for (const auto& [encoded, mime] : {std::pair{png, "image/png"}, std::pair{jpeg, "image/jpeg"}}) {
    GltfBuilder b = quad_scene();
    b.doc["images"] =
        json::array({{{"uri", std::string("data:") + mime + ";base64," + test::base64(encoded)}}});
    b.doc["textures"] = json::array({{{"source", 0}}});
    b.add_material({{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}});
    expect_error(load(b.gltf_embedded()), StatusCode::kResourceExhausted,
                 {"image 0", "65535 x 65535", "too large (the limit is 16384 per side"});
  }
}

}  // namespace
}  // namespace luxel::scene
