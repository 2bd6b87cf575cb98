// KHR_materials_unlit, KHR_materials_pbrSpecularGlossiness and
// KHR_texture_basisu on crafted files (GltfBuilder): what each becomes in the
// scene's metallic-roughness materials, checked against values computed here
// independently of the importer.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "common/half.h"
#include "gltf_builder.h"
#include "scene/gltf_import.h"

namespace luxel::scene {
namespace {

using test::GltfBuilder;
using test::json;
using test::kQuadIndices;
using test::kQuadPositions;

Result<Scene> load(const std::string& bytes) {
  return import_gltf_memory(bytes, "", "test.gltf");
}

std::string png_uri(int w, int h, const std::vector<uint8_t>& rgba) {
  return "data:image/png;base64," + test::base64(test::encode_png(w, h, 4, rgba));
}

// A quad using `material` (so that the file has a mesh, like a real one).
void add_quad(GltfBuilder& b, int material) {
  json prim = b.triangles(kQuadPositions, kQuadIndices);
  prim["material"] = material;
  b.add_node({{"mesh", b.add_mesh("m", {prim})}});
}

bool has_warning(const Scene& s, std::initializer_list<const char*> needles) {
  for (const std::string& line : s.import_stats.warnings) {
    bool all = true;
    for (const char* n : needles) all = all && line.find(n) != std::string::npos;
    if (all) return true;
  }
  return false;
}

double srgb_eotf(int code) {
  const double v = code / 255.0;
  return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

// --- KHR_materials_unlit ---------------------------------------------------

// Every core input except base colour, alpha and doubleSided is a fallback
// (the extension's "Extending Materials"): the unlit material is a Lambertian
// surface of albedo base colour, metallic 0, no specular layer, no emission.
TEST(MaterialExtensions, UnlitIsLambertianBaseColour) {
  GltfBuilder b;
  b.doc["images"] = json::array({{{"uri", png_uri(1, 1, {255, 128, 0, 255})}}});
  b.doc["textures"] = json::array({{{"source", 0}}});
  b.doc["extensionsUsed"] = json::array({"KHR_materials_unlit"});
  b.doc["extensionsRequired"] = json::array({"KHR_materials_unlit"});
  const int mat = b.add_material({{"name", "flat"},
                                  {"pbrMetallicRoughness",
                                   {{"baseColorFactor", {0.2, 0.5, 0.8, 0.7}},
                                    {"baseColorTexture", {{"index", 0}}},
                                    {"metallicFactor", 1.0},
                                    {"roughnessFactor", 0.1},
                                    {"metallicRoughnessTexture", {{"index", 0}}}}},
                                  {"emissiveFactor", {1, 1, 1}},
                                  {"emissiveTexture", {{"index", 0}}},
                                  {"normalTexture", {{"index", 0}}},
                                  {"alphaMode", "MASK"},
                                  {"alphaCutoff", 0.3},
                                  {"doubleSided", true},
                                  {"extensions", {{"KHR_materials_unlit", json::object()}}}});
  add_quad(b, mat);
  auto r = load(b.gltf_embedded());
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  const Material& m = r->materials[0];
  EXPECT_FLOAT_EQ(m.base_color_factor.x, 0.2f);
  EXPECT_FLOAT_EQ(m.base_color_factor.y, 0.5f);
  EXPECT_FLOAT_EQ(m.base_color_factor.z, 0.8f);
  EXPECT_FLOAT_EQ(m.base_color_factor.w, 0.7f);
  EXPECT_GE(m.base_color_texture.texture, 0) << "the base colour texture is the unlit colour";
  EXPECT_EQ(m.metallic_factor, 0.0f);
  EXPECT_EQ(m.metallic_roughness_texture.texture, -1);
  // No specular lobe: F0 = F90 = 0, so the diffuse weight 1 - F is 1.
  const Vec3 f0 = m.dielectric_specular_f0();
  EXPECT_EQ(f0.x, 0.0f);
  EXPECT_EQ(f0.y, 0.0f);
  EXPECT_EQ(f0.z, 0.0f);
  EXPECT_EQ(m.dielectric_specular_f90(), 0.0f);
  EXPECT_FALSE(m.is_emissive());
  EXPECT_EQ(m.emissive_texture.texture, -1);
  EXPECT_EQ(m.normal_texture.texture, -1);
  // Alpha coverage and doubleSided still apply.
  EXPECT_EQ(m.alpha_mode, AlphaMode::kMask);
  EXPECT_FLOAT_EQ(m.alpha_cutoff, 0.3f);
  EXPECT_TRUE(m.double_sided);
  EXPECT_TRUE(r->import_stats.warnings.empty()) << r->import_stats.warnings[0];
  ASSERT_EQ(r->textures.size(), 1u) << "only the base colour image is decoded";
}

// --- KHR_materials_pbrSpecularGlossiness -----------------------------------

// The Khronos conversion (the extension's examples, ConvertToMetallicRoughness),
// written out here from the README's description, not from the importer.
struct Expected {
  double base[3], metallic, roughness;
};
Expected khronos_convert(const double d[3], const double s[3], double gloss) {
  auto bright = [](const double c[3]) {
    return std::sqrt(0.299 * c[0] * c[0] + 0.587 * c[1] * c[1] + 0.114 * c[2] * c[2]);
  };
  const double strength = std::max({s[0], s[1], s[2]});
  const double bd = bright(d), bs = bright(s);
  double m = 0;
  if (bs >= 0.04) {
    // 0.04 m^2 + (bd (1 - strength) / 0.96 + bs - 0.08) m + (0.04 - bs) = 0
    const double qa = 0.04, qb = bd * (1 - strength) / 0.96 + bs - 0.08, qc = 0.04 - bs;
    m = std::clamp((-qb + std::sqrt(std::max(qb * qb - 4 * qa * qc, 0.0))) / (2 * qa), 0.0, 1.0);
  }
  Expected e{};
  for (int i = 0; i < 3; ++i) {
    const double fd = d[i] * (1 - strength) / 0.96 / std::max(1 - m, 1e-6);
    const double fs = (s[i] - 0.04 * (1 - m)) / std::max(m, 1e-6);
    e.base[i] = std::clamp(fd * (1 - m * m) + fs * m * m, 0.0, 1.0);
  }
  e.metallic = m;
  e.roughness = 1 - gloss;
  return e;
}

Result<Scene> load_spec_gloss(const json& ext) {
  GltfBuilder b;
  b.doc["extensionsUsed"] = json::array({"KHR_materials_pbrSpecularGlossiness"});
  // The core inputs are the fallback and must not be read.
  const int mat = b.add_material(
      {{"name", "sg"},
       {"pbrMetallicRoughness", {{"baseColorFactor", {0.9, 0.9, 0.9, 1}}, {"metallicFactor", 0.5}}},
       {"extensions", {{"KHR_materials_pbrSpecularGlossiness", ext}}}});
  add_quad(b, mat);
  return load(b.gltf_embedded());
}

TEST(MaterialExtensions, SpecGlossFactorsFollowKhronosConversion) {
  struct Case {
    double d[3], s[3], g;
  };
  const Case cases[] = {
      {{0.5, 0.5, 0.5}, {0.04, 0.04, 0.04}, 0.25},  // pure dielectric
      {{0, 0, 0}, {1.0, 0.766, 0.336}, 0.9},        // pure metal (the README's gold)
      {{0.3, 0.2, 0.1}, {0.5, 0.5, 0.5}, 0.3},      // in between
      {{0.8, 0.1, 0.1}, {0.02, 0.02, 0.02}, 0.0},   // below dielectric F0
  };
  for (const Case& c : cases) {
    auto r = load_spec_gloss({{"diffuseFactor", {c.d[0], c.d[1], c.d[2], 0.6}},
                              {"specularFactor", {c.s[0], c.s[1], c.s[2]}},
                              {"glossinessFactor", c.g}});
    ASSERT_TRUE(r.is_ok()) << r.status().to_string();
    const Material& m = r->materials[0];
    const Expected e = khronos_convert(c.d, c.s, c.g);
    EXPECT_NEAR(m.metallic_factor, e.metallic, 1e-6);
    EXPECT_NEAR(m.roughness_factor, e.roughness, 1e-6);
    EXPECT_NEAR(m.base_color_factor.x, e.base[0], 1e-6);
    EXPECT_NEAR(m.base_color_factor.y, e.base[1], 1e-6);
    EXPECT_NEAR(m.base_color_factor.z, e.base[2], 1e-6);
    EXPECT_FLOAT_EQ(m.base_color_factor.w, 0.6f) << "alpha is the diffuse alpha";
    EXPECT_EQ(m.base_color_texture.texture, -1);
    EXPECT_FLOAT_EQ(m.dielectric_f0(), 0.04f);
    EXPECT_TRUE(r->import_stats.warnings.empty()) << r->import_stats.warnings[0];
  }
  // The two ends, by their meaning rather than the formula.
  auto diel = load_spec_gloss(
      {{"diffuseFactor", {0.5, 0.25, 0.125, 1}}, {"specularFactor", {0.04, 0.04, 0.04}}});
  ASSERT_TRUE(diel.is_ok());
  EXPECT_NEAR(diel->materials[0].metallic_factor, 0.0, 1e-7);
  EXPECT_NEAR(diel->materials[0].base_color_factor.y, 0.25, 1e-6) << "base = diffuse";
  EXPECT_NEAR(diel->materials[0].roughness_factor, 0.0, 1e-7) << "glossiness defaults to 1";
  auto metal =
      load_spec_gloss({{"diffuseFactor", {0, 0, 0, 1}}, {"specularFactor", {0.9, 0.6, 0.3}}});
  ASSERT_TRUE(metal.is_ok());
  EXPECT_NEAR(metal->materials[0].metallic_factor, 1.0, 1e-6);
  EXPECT_NEAR(metal->materials[0].base_color_factor.x, 0.9, 1e-6) << "base = specular";
  EXPECT_NEAR(metal->materials[0].base_color_factor.z, 0.3, 1e-6);
}

// Metal-rough -> spec-gloss (the extension's ConvertToSpecularGlossiness:
// specular = mix(0.04, base, m), diffuse = base 0.96 (1 - m) / (1 - max
// specular)) and back is the identity for grey base colours, where the
// perceived brightness is the value itself.
TEST(MaterialExtensions, SpecGlossRoundTripsGreyMetalRough) {
  for (double base : {0.1, 0.6, 0.95})
    for (double metallic : {0.0, 0.25, 0.5, 0.8, 1.0}) {
      const double spec = 0.04 + (base - 0.04) * metallic;
      const double diffuse = base * 0.96 * (1 - metallic) / (1 - spec);
      auto r = load_spec_gloss({{"diffuseFactor", {diffuse, diffuse, diffuse, 1}},
                                {"specularFactor", {spec, spec, spec}},
                                {"glossinessFactor", 0.4}});
      ASSERT_TRUE(r.is_ok()) << r.status().to_string();
      const Material& m = r->materials[0];
      EXPECT_NEAR(m.metallic_factor, metallic, 2e-6) << base << " " << metallic;
      EXPECT_NEAR(m.base_color_factor.x, base, 2e-6) << base << " " << metallic;
      EXPECT_NEAR(m.roughness_factor, 0.6, 1e-6);
    }
}

// Textures sharing one mapping become a converted base colour and
// metallic-roughness texture pair, texel by texel (factors folded in).
TEST(MaterialExtensions, SpecGlossTexturesConvertedPerTexel) {
  GltfBuilder b;
  // Texel 0 dielectric-ish, texel 1 metal-ish; sRGB rgb, linear alpha.
  const std::vector<uint8_t> diffuse = {200, 100, 50, 255, 0, 0, 0, 128};
  const std::vector<uint8_t> specgloss = {56, 56, 56, 64, 230, 190, 120, 200};
  b.doc["images"] = json::array(
      {{{"uri", png_uri(2, 1, diffuse)}, {"name", "d"}}, {{"uri", png_uri(2, 1, specgloss)}}});
  b.doc["textures"] = json::array({{{"source", 0}}, {{"source", 1}}});
  const double df[4] = {0.9, 1.0, 0.8, 1.0}, sf[3] = {1.0, 0.9, 1.0}, gf = 0.8;
  const int mat = b.add_material({{"name", "sgt"},
                                  {"extensions",
                                   {{"KHR_materials_pbrSpecularGlossiness",
                                     {{"diffuseFactor", {df[0], df[1], df[2], df[3]}},
                                      {"specularFactor", {sf[0], sf[1], sf[2]}},
                                      {"glossinessFactor", gf},
                                      {"diffuseTexture", {{"index", 0}}},
                                      {"specularGlossinessTexture", {{"index", 1}}}}}}}});
  add_quad(b, mat);
  auto r = load(b.gltf_embedded());
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  const Material& m = r->materials[0];
  ASSERT_GE(m.base_color_texture.texture, 0);
  ASSERT_GE(m.metallic_roughness_texture.texture, 0);
  EXPECT_EQ(m.base_color_factor.x, 1.0f);
  EXPECT_EQ(m.metallic_factor, 1.0f);
  EXPECT_EQ(m.roughness_factor, 1.0f);
  ASSERT_EQ(r->textures.size(), 2u) << "only the converted pair is kept";
  const Texture& base = r->textures[static_cast<size_t>(m.base_color_texture.texture)];
  const Texture& mr = r->textures[static_cast<size_t>(m.metallic_roughness_texture.texture)];
  ASSERT_TRUE(base.has_pixels());
  ASSERT_EQ(base.width, 2);
  ASSERT_EQ(mr.width, 2);
  bool saw_metal = false, saw_dielectric = false;
  for (size_t t = 0; t < 2; ++t) {
    double d[3], s[3];
    for (int c = 0; c < 3; ++c) {
      d[c] = df[c] * srgb_eotf(diffuse[t * 4 + static_cast<size_t>(c)]);
      s[c] = sf[c] * srgb_eotf(specgloss[t * 4 + static_cast<size_t>(c)]);
    }
    const double g = gf * specgloss[t * 4 + 3] / 255.0;
    const Expected e = khronos_convert(d, s, g);
    const Vec4 bt = base.linear(t), mt = mr.linear(t);
    // Halves: relative rounding 2^-11.
    for (int c = 0; c < 3; ++c) EXPECT_NEAR((&bt.x)[c], e.base[c], 1e-3) << t << " " << c;
    EXPECT_NEAR(bt.w, df[3] * diffuse[t * 4 + 3] / 255.0, 1e-3);
    EXPECT_NEAR(mt.y, e.roughness, 1e-3);
    EXPECT_NEAR(mt.z, e.metallic, 1e-3);
    saw_metal = saw_metal || e.metallic > 0.9;
    saw_dielectric = saw_dielectric || e.metallic < 0.1;
  }
  EXPECT_TRUE(saw_metal && saw_dielectric) << "the texels cover both ends";
  EXPECT_NE(base.name.find("d + image[1]"), std::string::npos) << base.name;
  EXPECT_TRUE(r->import_stats.warnings.empty()) << r->import_stats.warnings[0];
}

// Textures on different UV sets cannot be combined texel by texel: factors
// converted, diffuseTexture as the base colour, and a warning saying so.
TEST(MaterialExtensions, SpecGlossTexturesOnDifferentUvSetsApproximated) {
  GltfBuilder b;
  b.doc["images"] = json::array({{{"uri", png_uri(1, 1, {255, 255, 255, 255})}}});
  b.doc["textures"] = json::array({{{"source", 0}}});
  const int mat =
      b.add_material({{"name", "split"},
                      {"extensions",
                       {{"KHR_materials_pbrSpecularGlossiness",
                         {{"diffuseFactor", {0.5, 0.5, 0.5, 1}},
                          {"specularFactor", {0.04, 0.04, 0.04}},
                          {"diffuseTexture", {{"index", 0}}},
                          {"specularGlossinessTexture", {{"index", 0}, {"texCoord", 1}}}}}}}});
  add_quad(b, mat);
  auto r = load(b.gltf_embedded());
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  const Material& m = r->materials[0];
  EXPECT_GE(m.base_color_texture.texture, 0);
  EXPECT_EQ(m.metallic_roughness_texture.texture, -1);
  EXPECT_NEAR(m.base_color_factor.x, 0.5, 1e-6);
  EXPECT_NEAR(m.metallic_factor, 0.0, 1e-7);
  EXPECT_TRUE(has_warning(
      *r, {"material 'split'", "specularGlossinessTexture is left out", "map UVs differently"}));
}

TEST(MaterialExtensions, SpecGlossBadFactorNamed) {
  auto r = load_spec_gloss({{"specularFactor", {0.5, 2.0, 0.5}}});
  ASSERT_FALSE(r.is_ok());
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find("material 'sg'"), std::string::npos);
  EXPECT_NE(r.status().message().find("specularFactor"), std::string::npos);
}

// --- KHR_texture_basisu ------------------------------------------------------

// A texture with a KTX2 image in the extension and `source` = PNG fallback;
// without `fallback` the core source is omitted.
GltfBuilder basisu_file(bool fallback) {
  GltfBuilder b;
  const std::string ktx2 = "\xABKTX 20\xBB\r\n\x1A\n not a real payload";
  const int view = b.add_view(ktx2.data(), ktx2.size());
  b.doc["images"] = json::array({{{"uri", png_uri(3, 2, std::vector<uint8_t>(24, 200))}},
                                 {{"mimeType", "image/ktx2"}, {"bufferView", view}}});
  json tex = {{"name", "bricks"}, {"extensions", {{"KHR_texture_basisu", {{"source", 1}}}}}};
  if (fallback) tex["source"] = 0;
  b.doc["textures"] = json::array({tex});
  b.doc["extensionsUsed"] = json::array({"KHR_texture_basisu"});
  const int mat = b.add_material(
      {{"name", "wall"}, {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}});
  add_quad(b, mat);
  return b;
}

TEST(MaterialExtensions, BasisuUsesThePngFallback) {
  auto r = load(basisu_file(true).gltf_embedded());
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  const Material& m = r->materials[0];
  ASSERT_GE(m.base_color_texture.texture, 0);
  const Texture& t = r->textures[static_cast<size_t>(m.base_color_texture.texture)];
  EXPECT_EQ(t.gltf_image, 0);
  EXPECT_EQ(t.width, 3);
  EXPECT_EQ(t.height, 2);
  EXPECT_TRUE(r->import_stats.warnings.empty()) << r->import_stats.warnings[0];
}

TEST(MaterialExtensions, BasisuWithoutFallbackNamesTheTexture) {
  auto r = load(basisu_file(false).gltf_embedded());
  ASSERT_FALSE(r.is_ok());
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  for (const char* needle :
       {"material 'wall'", "texture 0 'bricks'", "KTX2", "not decoded", "fallback", "missing"})
    EXPECT_NE(r.status().message().find(needle), std::string::npos)
        << "'" << needle << "' not in: " << r.status().message();
}

TEST(MaterialExtensions, BasisuRequiredIsRefusedByName) {
  GltfBuilder b = basisu_file(false);
  b.doc["extensionsRequired"] = json::array({"KHR_texture_basisu"});
  auto r = load(b.gltf_embedded());
  ASSERT_FALSE(r.is_ok());
  EXPECT_NE(r.status().message().find("KHR_texture_basisu is required"), std::string::npos)
      << r.status().message();
  EXPECT_NE(r.status().message().find("not decoded"), std::string::npos);
}

}  // namespace
}  // namespace luxel::scene
