// See materials.h. Factors are validated (finite, in range) because later
// stages feed them to the path tracer unchecked.
#include "scene/materials.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include "scene/spec_gloss.h"
#include "scene/textures.h"

namespace luxel::scene::detail {
namespace {

class TextureTable {
 public:
  TextureTable(const tinygltf::Model& model, const ImportOptions& options, ImportBudget* budget,
               Scene* scene)
      : model_(model),
        options_(options),
        budget_(budget),
        scene_(scene),
        pixel_budget_(options.max_total_texture_pixels) {}

  std::vector<std::string>& warnings() { return scene_->import_stats.warnings; }

  // Resolves a textureInfo of material `what` ("material 'x' (material[1])
  // baseColorTexture") to a TextureRef, decoding the image on first use.
  Result<TextureRef> resolve(const tinygltf::TextureInfo& info, ColorSpace space,
                             const std::string& what) {
    return resolve(info.index, info.texCoord, info.extensions, space, what);
  }

  Result<TextureRef> resolve(int texture_index, int texcoord, const tinygltf::ExtensionMap& ext,
                             ColorSpace space, const std::string& what) {
    TextureRef ref;
    auto image = prepare(texture_index, texcoord, ext, what, &ref);
    if (!image) return image.status();
    if (*image < 0) return ref;
    const auto key = std::make_pair(*image, space);
    auto it = decoded_.find(key);
    if (it == decoded_.end()) {
      auto tex = decode_texture(model_, *image, space, options_, &pixel_budget_, budget_);
      if (!tex) return Status(tex.status().code(), what + ": " + tex.status().message());
      it = decoded_.emplace(key, add(std::move(*tex))).first;
    }
    ref.texture = it->second;
    return ref;
  }

  // A textureInfo's mapping and its decoded image, kept out of the scene:
  // for inputs that are combined into new textures at import. The texture is
  // empty (no size) when the textureInfo names no image.
  Result<std::pair<TextureRef, Texture>> decode_detached(int texture_index, int texcoord,
                                                         const tinygltf::ExtensionMap& ext,
                                                         ColorSpace space,
                                                         const std::string& what) {
    std::pair<TextureRef, Texture> out;
    auto image = prepare(texture_index, texcoord, ext, what, &out.first);
    if (!image) return image.status();
    if (*image < 0) return out;
    auto tex = decode_texture(model_, *image, space, options_, &pixel_budget_, budget_);
    if (!tex) return Status(tex.status().code(), what + ": " + tex.status().message());
    out.second = std::move(*tex);
    return out;
  }

  // Adds a texture made at import (counted against the pixel budget, like a
  // decoded one) and returns its index in scene->textures.
  Result<int> add_made(Texture tex, const std::string& what) {
    const uint64_t pixels = tex.texel_count();
    if (pixels > pixel_budget_)
      return resource_exhausted(
          strprintf("%s: %d x %d converted pixels exceed the import's "
                    "texture budget",
                    what.c_str(), tex.width, tex.height));
    pixel_budget_ -= pixels;
    LUXEL_RETURN_IF_ERROR(budget_->reserve(
        mul_sat(pixels, tex.format == TexelFormat::kRGBA16F ? 8 : 4),
        strprintf("%s: %d x %d converted pixels", what.c_str(), tex.width, tex.height)));
    return add(std::move(tex));
  }

 private:
  int add(Texture tex) {
    scene_->textures.push_back(std::move(tex));
    return static_cast<int>(scene_->textures.size() - 1);
  }

  // "texture 2 'bricks'" / "texture 2" for messages.
  std::string texture_label(int texture_index) const {
    const std::string& n = model_.textures[static_cast<size_t>(texture_index)].name;
    return n.empty() ? strprintf("texture %d", texture_index)
                     : strprintf("texture %d '%s'", texture_index, n.c_str());
  }

  // Checks textureInfo (texture, texCoord, sampler, KHR_texture_transform),
  // fills ref's mapping and returns the glTF image to decode, or -1 when the
  // material is to use its factors alone.
  Result<int> prepare(int texture_index, int texcoord, const tinygltf::ExtensionMap& ext,
                      const std::string& what, TextureRef* ref) {
    if (texture_index < 0) return -1;
    if (static_cast<size_t>(texture_index) >= model_.textures.size()) {
      return invalid_argument(strprintf("%s: texture %d does not exist (%zu textures)",
                                        what.c_str(), texture_index, model_.textures.size()));
    }
    if (texcoord != 0 && texcoord != 1) {
      return invalid_argument(
          strprintf("%s: texCoord %d is not supported (0 or 1)", what.c_str(), texcoord));
    }
    const tinygltf::Texture& texture = model_.textures[static_cast<size_t>(texture_index)];
    const int image = texture.source;
    if (image < 0) {
      // KHR_texture_basisu ("glTF Schema Updates"): a texture's core
      // source is the PNG/JPEG fallback for clients without the extension
      // ("Using Without a Fallback" omits it). Without one only the KTX2 image is left, which is
      // not decoded here, and leaving out e.g. a base colour map would bake the wrong albedo
      // without anyone noticing.
      if (texture.extensions.count("KHR_texture_basisu"))
        return invalid_argument(
            strprintf("%s: %s has only a KHR_texture_basisu image (KTX2 / Basis Universal "
                      "images are not decoded) and its fallback source (a PNG or JPEG image "
                      "in the texture's 'source') is missing",
                      what.c_str(), texture_label(texture_index).c_str()));
      // glTF 2.0 §5.29: source is optional (an extension may supply the
      // image); without one the material uses its factors alone.
      warnings().push_back(
          strprintf("%s: texture %d has no source image; the texture is left "
                    "out (factors only)",
                    what.c_str(), texture_index));
      return -1;
    }
    if (static_cast<size_t>(image) >= model_.images.size()) {
      return invalid_argument(
          strprintf("%s: texture %d: source image %d does not exist (%zu images)", what.c_str(),
                    texture_index, image, model_.images.size()));
    }
    ref->texcoord = texcoord;
    LUXEL_RETURN_IF_ERROR(read_sampler(texture_index, what, ref));
    LUXEL_RETURN_IF_ERROR(read_transform(ext, what, ref));
    for (const auto& [name, value] : ext)
      if (name != "KHR_texture_transform")
        warnings().push_back(what + ": texture extension " + name + " is not supported (ignored)");
    return image;
  }

  // glTF 2.0 §5.26: wrapS / wrapT are 33071 (CLAMP_TO_EDGE), 33648
  // (MIRRORED_REPEAT) or 10497 (REPEAT, the default). Filters are not read:
  // the bake filters bilinearly (magnification LINEAR) without mipmaps.
  Status read_sampler(int texture_index, const std::string& what, TextureRef* ref) {
    const int sampler = model_.textures[static_cast<size_t>(texture_index)].sampler;
    if (sampler < 0) return Status::ok();
    if (static_cast<size_t>(sampler) >= model_.samplers.size())
      return invalid_argument(strprintf("%s: texture %d names sampler %d (%zu samplers)",
                                        what.c_str(), texture_index, sampler,
                                        model_.samplers.size()));
    const auto& sm = model_.samplers[static_cast<size_t>(sampler)];
    auto mode = [&](int v, const char* field, WrapMode* out) -> Status {
      switch (v) {
        case 10497:
          *out = WrapMode::kRepeat;
          return Status::ok();
        case 33071:
          *out = WrapMode::kClampToEdge;
          return Status::ok();
        case 33648:
          *out = WrapMode::kMirroredRepeat;
          return Status::ok();
        default:
          return invalid_argument(
              strprintf("%s: sampler %d %s %d is not REPEAT (10497), CLAMP_TO_EDGE (33071) or "
                        "MIRRORED_REPEAT (33648)",
                        what.c_str(), sampler, field, v));
      }
    };
    LUXEL_RETURN_IF_ERROR(mode(sm.wrapS, "wrapS", &ref->wrap_s));
    return mode(sm.wrapT, "wrapT", &ref->wrap_t);
  }

  // KHR_texture_transform: offset [0, 0], rotation 0, scale [1, 1], and a
  // texCoord that overrides the textureInfo's.
  Status read_transform(const tinygltf::ExtensionMap& ext, const std::string& what,
                        TextureRef* ref) {
    auto it = ext.find("KHR_texture_transform");
    if (it == ext.end()) return Status::ok();
    const tinygltf::Value& v = it->second;
    if (!v.IsObject()) return invalid_argument(what + ": KHR_texture_transform is not an object");
    auto vec2 = [&](const char* key, Vec2* out) -> Status {
      if (!v.Has(key)) return Status::ok();
      const auto& a = v.Get(key);
      if (!a.IsArray() || a.ArrayLen() != 2 || !a.Get(0).IsNumber() || !a.Get(1).IsNumber())
        return invalid_argument(
            strprintf("%s: KHR_texture_transform %s must be 2 numbers", what.c_str(), key));
      const double x = a.Get(0).GetNumberAsDouble(), y = a.Get(1).GetNumberAsDouble();
      if (!std::isfinite(x) || !std::isfinite(y) || std::fabs(x) > 3e38 || std::fabs(y) > 3e38)
        return invalid_argument(
            strprintf("%s: KHR_texture_transform %s is not finite", what.c_str(), key));
      *out = {static_cast<float>(x), static_cast<float>(y)};
      return Status::ok();
    };
    LUXEL_RETURN_IF_ERROR(vec2("offset", &ref->offset));
    LUXEL_RETURN_IF_ERROR(vec2("scale", &ref->scale));
    if (v.Has("rotation")) {
      const auto& r = v.Get("rotation");
      if (!r.IsNumber() || !std::isfinite(r.GetNumberAsDouble()) ||
          std::fabs(r.GetNumberAsDouble()) > 1e6)
        return invalid_argument(what + ": KHR_texture_transform rotation is not a finite number");
      ref->rotation = static_cast<float>(r.GetNumberAsDouble());
    }
    if (v.Has("texCoord")) {
      const auto& t = v.Get("texCoord");
      if (!t.IsInt() || (t.Get<int>() != 0 && t.Get<int>() != 1))
        return invalid_argument(what +
                                ": KHR_texture_transform texCoord is not 0 or 1 (the UV sets "
                                "the bake reads)");
      ref->texcoord = t.Get<int>();
    }
    ref->has_transform = true;
    return Status::ok();
  }

  const tinygltf::Model& model_;
  const ImportOptions& options_;
  ImportBudget* budget_;
  Scene* scene_;
  uint64_t pixel_budget_;
  std::map<std::pair<int, ColorSpace>, int> decoded_;
};

bool finite_all(const std::vector<double>& v) {
  for (double x : v) {
    if (!std::isfinite(x)) return false;
  }
  return true;
}

Status check_factor(const std::string& label, const char* field, double v, double lo, double hi) {
  if (!std::isfinite(v) || v < lo || v > hi) {
    return invalid_argument(
        strprintf("%s: %s %g is outside [%g, %g]", label.c_str(), field, v, lo, hi));
  }
  return Status::ok();
}

// A textureInfo inside an extension object (tinygltf parses only the core
// ones): index, texCoord and its own extensions (KHR_texture_transform).
struct ExtTextureInfo {
  int index = -1;
  int texcoord = 0;
  tinygltf::ExtensionMap extensions;
};

Result<ExtTextureInfo> ext_texture_info(const tinygltf::Value& v, const char* key,
                                        const std::string& what) {
  ExtTextureInfo info;
  if (!v.Has(key)) return info;
  const tinygltf::Value& t = v.Get(key);
  if (!t.IsObject() || !t.Has("index") || !t.Get("index").IsInt() || t.Get("index").Get<int>() < 0)
    return invalid_argument(what + " is not a textureInfo with a texture index");
  info.index = t.Get("index").Get<int>();
  if (t.Has("texCoord")) {
    if (!t.Get("texCoord").IsInt()) return invalid_argument(what + ": texCoord is not an integer");
    info.texcoord = t.Get("texCoord").Get<int>();
  }
  if (t.Has("extensions") && t.Get("extensions").IsObject()) {
    const tinygltf::Value& e = t.Get("extensions");
    for (const std::string& name : e.Keys()) info.extensions[name] = e.Get(name);
  }
  return info;
}

// `n` numbers in [0, 1] at v[key] into out; out is left as it is when absent.
Status ext_factors(const tinygltf::Value& v, const char* key, size_t n, const std::string& label,
                   float* out) {
  if (!v.Has(key)) return Status::ok();
  const tinygltf::Value& a = v.Get(key);
  if (n == 1) {
    if (!a.IsNumber())
      return invalid_argument(strprintf("%s: %s is not a number", label.c_str(), key));
    LUXEL_RETURN_IF_ERROR(check_factor(label, key, a.GetNumberAsDouble(), 0, 1));
    out[0] = static_cast<float>(a.GetNumberAsDouble());
    return Status::ok();
  }
  if (!a.IsArray() || a.ArrayLen() != n)
    return invalid_argument(strprintf("%s: %s must be %zu numbers", label.c_str(), key, n));
  for (size_t i = 0; i < n; ++i) {
    if (!a.Get(static_cast<int>(i)).IsNumber())
      return invalid_argument(strprintf("%s: %s must be %zu numbers", label.c_str(), key, n));
    const double x = a.Get(static_cast<int>(i)).GetNumberAsDouble();
    LUXEL_RETURN_IF_ERROR(check_factor(label, key, x, 0, 1));
    out[i] = static_cast<float>(x);
  }
  return Status::ok();
}

bool same_mapping(const TextureRef& a, const TextureRef& b) {
  return a.texcoord == b.texcoord && a.wrap_s == b.wrap_s && a.wrap_t == b.wrap_t &&
         a.has_transform == b.has_transform && a.offset.x == b.offset.x &&
         a.offset.y == b.offset.y && a.rotation == b.rotation && a.scale.x == b.scale.x &&
         a.scale.y == b.scale.y;
}

// KHR_materials_pbrSpecularGlossiness (spec_gloss.h): replaces the core
// metallic-roughness inputs, which are the file's fallback for viewers
// without the extension and are not read. The extension's textures are
// converted per texel into a new base colour and metallic-roughness texture
// pair when they share one UV mapping; otherwise (different UV sets,
// samplers or transforms, which no single texture can hold) the factors are
// converted and diffuseTexture becomes the base colour texture, with a
// warning that names what was approximated.
Status convert_spec_gloss(const tinygltf::Value& v, const std::string& label, TextureTable* table,
                          Material* m) {
  const std::string what = label + " KHR_materials_pbrSpecularGlossiness";
  if (!v.IsObject()) return invalid_argument(what + " is not an object");
  SpecGlossInputs in;
  float diffuse[4] = {1, 1, 1, 1}, specular[3] = {1, 1, 1}, gloss = 1;
  LUXEL_RETURN_IF_ERROR(ext_factors(v, "diffuseFactor", 4, what, diffuse));
  LUXEL_RETURN_IF_ERROR(ext_factors(v, "specularFactor", 3, what, specular));
  LUXEL_RETURN_IF_ERROR(ext_factors(v, "glossinessFactor", 1, what, &gloss));
  in.factors.diffuse = {diffuse[0], diffuse[1], diffuse[2], diffuse[3]};
  in.factors.specular = {specular[0], specular[1], specular[2]};
  in.factors.glossiness = gloss;
  // Factors alone: exact, and the textureless case.
  const MetalRough f = spec_gloss_to_metal_rough(in.factors);
  m->base_color_factor = f.base_color;
  m->metallic_factor = f.metallic;
  m->roughness_factor = f.roughness;

  auto dinfo = ext_texture_info(v, "diffuseTexture", what + " diffuseTexture");
  if (!dinfo) return dinfo.status();
  auto sinfo =
      ext_texture_info(v, "specularGlossinessTexture", what + " specularGlossinessTexture");
  if (!sinfo) return sinfo.status();
  // Both textures are sRGB-encoded colour (the extension's diffuseTexture
  // and specularGlossinessTexture sections); the glossiness in the
  // specular texture's alpha is linear, as every decoded alpha is.
  auto d = table->decode_detached(dinfo->index, dinfo->texcoord, dinfo->extensions,
                                  ColorSpace::kSRGB, what + " diffuseTexture");
  if (!d) return d.status();
  auto sg = table->decode_detached(sinfo->index, sinfo->texcoord, sinfo->extensions,
                                   ColorSpace::kSRGB, what + " specularGlossinessTexture");
  if (!sg) return sg.status();
  const bool has_d = d->second.texel_count() > 0, has_sg = sg->second.texel_count() > 0;
  if (!has_d && !has_sg) return Status::ok();
  if (has_d && has_sg && !same_mapping(d->first, sg->first)) {
    table->warnings().push_back(
        what +
        ": diffuseTexture and specularGlossinessTexture map UVs differently (texCoord, sampler "
        "or KHR_texture_transform), so they cannot be converted per texel: metallic and "
        "roughness come from the factors alone (specularGlossinessTexture is left out) and "
        "diffuseTexture times the converted factor is the base colour");
    auto base = table->resolve(dinfo->index, dinfo->texcoord, dinfo->extensions, ColorSpace::kSRGB,
                               what + " diffuseTexture");
    if (!base) return base.status();
    m->base_color_texture = *base;
    return Status::ok();
  }
  in.diffuse = has_d ? &d->second : nullptr;
  in.specular_glossiness = has_sg ? &sg->second : nullptr;
  const TextureRef mapping = has_d ? d->first : sg->first;
  ConvertedTextures out;
  if (d->second.has_pixels() || sg->second.has_pixels()) {
    out = convert_spec_gloss_textures(in);
  } else {  // ImportOptions::decode_textures false: sizes only
    for (Texture* t : {&out.base_color, &out.metallic_roughness}) {
      t->width = std::max(d->second.width, sg->second.width);
      t->height = std::max(d->second.height, sg->second.height);
      t->format = TexelFormat::kRGBA16F;
    }
  }
  const std::string inputs = has_d && has_sg ? d->second.name + " + " + sg->second.name
                             : has_d         ? d->second.name
                                             : sg->second.name;
  out.base_color.name = inputs + " (specular-glossiness -> base colour)";
  out.metallic_roughness.name = inputs + " (specular-glossiness -> metallic-roughness)";
  auto base = table->add_made(std::move(out.base_color), what);
  if (!base) return base.status();
  auto mr = table->add_made(std::move(out.metallic_roughness), what);
  if (!mr) return mr.status();
  m->base_color_texture = mapping;
  m->base_color_texture.texture = *base;
  m->metallic_roughness_texture = mapping;
  m->metallic_roughness_texture.texture = *mr;
  // The factors are folded into the texels.
  m->base_color_factor = {1, 1, 1, 1};
  m->metallic_factor = 1;
  m->roughness_factor = 1;
  return Status::ok();
}

// See the KHR_materials_unlit comment in convert().
Result<Material> convert_unlit(const tinygltf::Material& gm, const std::string& label, Material m,
                               TextureTable* table) {
  m.metallic_factor = 0.0f;
  m.roughness_factor = 1.0f;
  m.ior = 1.5f;
  m.specular_factor = 0.0f;
  m.specular_color_factor = {1, 1, 1};
  m.emissive_factor = {0, 0, 0};
  m.emissive_strength = 1.0f;
  auto base = table->resolve(gm.pbrMetallicRoughness.baseColorTexture, ColorSpace::kSRGB,
                             label + " baseColorTexture");
  if (!base) return base.status();
  m.base_color_texture = *base;
  // The extension's implementation note leaves a second shading model on
  // the same material undefined; unlit wins and the others are named.
  for (const auto& [name, value] : gm.extensions)
    if (name != "KHR_materials_unlit")
      table->warnings().push_back(label + ": material extension " + name +
                                  " is ignored (the material is KHR_materials_unlit: base colour "
                                  "and alpha only)");
  return m;
}

Result<Material> convert(const tinygltf::Model& model, int index, TextureTable* table) {
  const auto& gm = model.materials[static_cast<size_t>(index)];
  const std::string label = gm.name.empty()
                                ? strprintf("material[%d]", index)
                                : strprintf("material '%s' (material[%d])", gm.name.c_str(), index);
  Material m;
  m.name = gm.name.empty() ? strprintf("material[%d]", index) : gm.name;
  const auto& pbr = gm.pbrMetallicRoughness;

  if (pbr.baseColorFactor.size() != 4 || !finite_all(pbr.baseColorFactor)) {
    return invalid_argument(label + ": baseColorFactor must be 4 finite numbers");
  }
  for (double v : pbr.baseColorFactor)
    LUXEL_RETURN_IF_ERROR(check_factor(label, "baseColorFactor", v, 0, 1));
  m.base_color_factor = {
      static_cast<float>(pbr.baseColorFactor[0]), static_cast<float>(pbr.baseColorFactor[1]),
      static_cast<float>(pbr.baseColorFactor[2]), static_cast<float>(pbr.baseColorFactor[3])};
  LUXEL_RETURN_IF_ERROR(check_factor(label, "metallicFactor", pbr.metallicFactor, 0, 1));
  LUXEL_RETURN_IF_ERROR(check_factor(label, "roughnessFactor", pbr.roughnessFactor, 0, 1));
  m.metallic_factor = static_cast<float>(pbr.metallicFactor);
  m.roughness_factor = static_cast<float>(pbr.roughnessFactor);

  if (gm.emissiveFactor.size() != 3 || !finite_all(gm.emissiveFactor)) {
    return invalid_argument(label + ": emissiveFactor must be 3 finite numbers");
  }
  // The spec bounds emissiveFactor to [0,1]; older exporters wrote larger
  // values to mean a stronger light, which we keep.
  for (double v : gm.emissiveFactor) {
    LUXEL_RETURN_IF_ERROR(check_factor(label, "emissiveFactor", v, 0, HUGE_VAL));
  }
  m.emissive_factor = {static_cast<float>(gm.emissiveFactor[0]),
                       static_cast<float>(gm.emissiveFactor[1]),
                       static_cast<float>(gm.emissiveFactor[2])};
  auto ext = gm.extensions.find("KHR_materials_emissive_strength");
  if (ext != gm.extensions.end() && ext->second.IsObject() && ext->second.Has("emissiveStrength")) {
    const auto& v = ext->second.Get("emissiveStrength");
    if (!v.IsNumber()) return invalid_argument(label + ": emissiveStrength is not a number");
    const double s = v.GetNumberAsDouble();
    LUXEL_RETURN_IF_ERROR(check_factor(label, "emissiveStrength", s, 0, 3.0e38));
    m.emissive_strength = static_cast<float>(s);
  }

  // KHR_materials_ior: ior >= 1, or 0 (f0 = 1), per the extension's spec.
  ext = gm.extensions.find("KHR_materials_ior");
  if (ext != gm.extensions.end() && ext->second.IsObject() && ext->second.Has("ior")) {
    const auto& v = ext->second.Get("ior");
    if (!v.IsNumber()) return invalid_argument(label + ": KHR_materials_ior ior is not a number");
    const double ior = v.GetNumberAsDouble();
    if (!(std::isfinite(ior) && (ior == 0.0 || (ior >= 1.0 && ior <= 1e6))))
      return invalid_argument(
          strprintf("%s: KHR_materials_ior ior %g is not 0 or in [1, 1e6]", label.c_str(), ior));
    m.ior = static_cast<float>(ior);
  }

  // KHR_materials_specular: specularFactor in [0, 1], specularColorFactor
  // >= 0 (values above 1 are allowed: F0(ior) times them is clamped to 1).
  ext = gm.extensions.find("KHR_materials_specular");
  if (ext != gm.extensions.end() && ext->second.IsObject()) {
    const auto& v = ext->second;
    if (v.Has("specularFactor")) {
      const auto& f = v.Get("specularFactor");
      if (!f.IsNumber()) return invalid_argument(label + ": specularFactor is not a number");
      LUXEL_RETURN_IF_ERROR(check_factor(label, "specularFactor", f.GetNumberAsDouble(), 0, 1));
      m.specular_factor = static_cast<float>(f.GetNumberAsDouble());
    }
    if (v.Has("specularColorFactor")) {
      const auto& c = v.Get("specularColorFactor");
      if (!c.IsArray() || c.ArrayLen() != 3)
        return invalid_argument(label + ": specularColorFactor must be 3 numbers");
      float rgb[3];
      for (int i = 0; i < 3; ++i) {
        if (!c.Get(i).IsNumber())
          return invalid_argument(label + ": specularColorFactor must be 3 numbers");
        const double x = c.Get(i).GetNumberAsDouble();
        LUXEL_RETURN_IF_ERROR(check_factor(label, "specularColorFactor", x, 0, 3.0e38));
        rgb[i] = static_cast<float>(x);
      }
      m.specular_color_factor = {rgb[0], rgb[1], rgb[2]};
    }
    // The textures would need two more slots per material; named instead.
    for (const char* tex : {"specularTexture", "specularColorTexture"})
      if (v.Has(tex))
        table->warnings().push_back(label + ": KHR_materials_specular " + tex +
                                    " is not supported (the factor alone is used)");
  }

  m.double_sided = gm.doubleSided;
  if (gm.alphaMode == "OPAQUE" || gm.alphaMode.empty()) {
    m.alpha_mode = AlphaMode::kOpaque;
  } else if (gm.alphaMode == "MASK") {
    m.alpha_mode = AlphaMode::kMask;
  } else if (gm.alphaMode == "BLEND") {
    m.alpha_mode = AlphaMode::kBlend;
  } else {
    return invalid_argument(strprintf("%s: alphaMode '%s' is not OPAQUE, MASK or BLEND",
                                      label.c_str(), gm.alphaMode.c_str()));
  }
  LUXEL_RETURN_IF_ERROR(check_factor(label, "alphaCutoff", gm.alphaCutoff, 0, 3.0e38));
  m.alpha_cutoff = static_cast<float>(gm.alphaCutoff);

  // KHR_materials_unlit ("Extending Materials"): base colour and alpha
  // only; every other input of the core model is a fallback for viewers
  // without the extension. An unlit surface still occludes and still gets
  // its lightmap; for the light that bounces off it the bake reads it as
  // what its base colour says it reflects: a Lambertian diffuse surface of
  // albedo base colour, metallic 0, no specular layer (F0 = F90 = 0 through
  // KHR_materials_specular's specularFactor 0) and no emission.
  if (gm.extensions.count("KHR_materials_unlit"))
    return convert_unlit(gm, label, std::move(m), table);

  auto sg_ext = gm.extensions.find("KHR_materials_pbrSpecularGlossiness");
  if (sg_ext != gm.extensions.end()) {
    // The conversion assumes the core's dielectric F0 of 0.04 (spec_gloss.h);
    // the specular colour already says what ior / specular would change.
    for (const char* other : {"KHR_materials_ior", "KHR_materials_specular"})
      if (gm.extensions.count(other))
        table->warnings().push_back(label + ": material extension " + other +
                                    " is ignored beside KHR_materials_pbrSpecularGlossiness "
                                    "(its specular colour is the F0)");
    m.ior = 1.5f;
    m.specular_factor = 1.0f;
    m.specular_color_factor = {1, 1, 1};
    LUXEL_RETURN_IF_ERROR(convert_spec_gloss(sg_ext->second, label, table, &m));
  } else {
    auto base =
        table->resolve(pbr.baseColorTexture, ColorSpace::kSRGB, label + " baseColorTexture");
    if (!base) return base.status();
    m.base_color_texture = *base;
    auto mr = table->resolve(pbr.metallicRoughnessTexture, ColorSpace::kLinear,
                             label + " metallicRoughnessTexture");
    if (!mr) return mr.status();
    m.metallic_roughness_texture = *mr;
  }
  auto em = table->resolve(gm.emissiveTexture, ColorSpace::kSRGB, label + " emissiveTexture");
  if (!em) return em.status();
  m.emissive_texture = *em;

  // glTF 2.0 §3.9.3 / §5.22 (material.normalTextureInfo): linear RGB, the
  // scale multiplies the map's X and Y.
  auto nt =
      table->resolve(gm.normalTexture.index, gm.normalTexture.texCoord, gm.normalTexture.extensions,
                     ColorSpace::kLinear, label + " normalTexture");
  if (!nt) return nt.status();
  m.normal_texture = *nt;
  if (!std::isfinite(gm.normalTexture.scale) || std::fabs(gm.normalTexture.scale) > 1e6)
    return invalid_argument(
        strprintf("%s: normalTexture scale %g is not a finite number in "
                  "[-1e6, 1e6]",
                  label.c_str(), gm.normalTexture.scale));
  m.normal_scale = static_cast<float>(gm.normalTexture.scale);

  // Inputs that change baked light but are not modelled yet, by name.
  auto& warnings = table->warnings();
  for (const auto& [name, value] : gm.extensions)
    if (!is_supported_extension(name))
      warnings.push_back(label + ": material extension " + name +
                         " is not supported (the metallic-roughness core is used)");
  return m;
}

}  // namespace

bool is_supported_extension(const std::string& name) {
  return name == "KHR_lights_punctual" || name == "KHR_materials_emissive_strength" ||
         name == "KHR_materials_ior" || name == "KHR_texture_transform" ||
         name == "KHR_materials_specular" || name == "KHR_materials_unlit" ||
         name == "KHR_materials_pbrSpecularGlossiness" || name == "KHR_texture_basisu";
}

Status convert_materials(const tinygltf::Model& model, const ImportOptions& options,
                         ImportBudget* budget, Scene* scene) {
  if (options.decode_textures && !model.materials.empty()) {
    // The texels every texture's image keeps, from their headers, checked
    // against the budget before the first is decoded (each decode reserves
    // its own again): a file whose images do not fit together is refused
    // without decoding any. The images of textures no material uses are
    // counted too.
    std::vector<uint8_t> counted(model.images.size(), 0);
    uint64_t bytes = 0;
    size_t images = 0;
    std::string named;
    for (const auto& t : model.textures) {
      if (t.source < 0 || static_cast<size_t>(t.source) >= model.images.size() ||
          counted[static_cast<size_t>(t.source)]++)
        continue;
      int w = 0, h = 0;
      const uint64_t b = declared_texel_bytes(model, t.source, options, &w, &h);
      if (b == 0) continue;
      bytes = add_sat(bytes, b);
      if (++images <= 4)
        named += strprintf("%s%s (%d x %d)", named.empty() ? "" : ", ",
                           image_label(model, t.source).c_str(), w, h);
    }
    if (images > 4) named += strprintf(" and %zu more", images - 4);
    if (bytes > 0) {
      LUXEL_RETURN_IF_ERROR(budget->reserve(
          bytes, strprintf("%s: decoded texels of the textures' images", named.c_str())));
      budget->release(bytes);
    }
  }
  TextureTable table(model, options, budget, scene);
  for (size_t i = 0; i < model.materials.size(); ++i) {
    auto m = convert(model, static_cast<int>(i), &table);
    if (!m) return m.status();
    scene->materials.push_back(std::move(*m));
  }
  return Status::ok();
}

}  // namespace luxel::scene::detail
