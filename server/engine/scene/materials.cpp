// See materials.h. Factors are validated (finite, in range) because later
// stages feed them to the path tracer unchecked.
#include "scene/materials.h"

#include <cmath>
#include <map>
#include <utility>

#include "scene/textures.h"

namespace luxel::scene::detail {
namespace {

class TextureTable {
 public:
  TextureTable(const tinygltf::Model& model, const ImportOptions& options, Scene* scene)
      : model_(model),
        options_(options),
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
    if (texture_index < 0) return ref;
    if (static_cast<size_t>(texture_index) >= model_.textures.size()) {
      return invalid_argument(strprintf("%s: texture %d does not exist (%zu textures)",
                                        what.c_str(), texture_index, model_.textures.size()));
    }
    if (texcoord != 0 && texcoord != 1) {
      return invalid_argument(
          strprintf("%s: texCoord %d is not supported (0 or 1)", what.c_str(), texcoord));
    }
    const int image = model_.textures[static_cast<size_t>(texture_index)].source;
    if (image < 0) {
      // glTF 2.0 §5.29: source is optional (an extension may supply the
      // image); without one the material uses its factors alone.
      warnings().push_back(
          strprintf("%s: texture %d has no source image; the texture is left "
                    "out (factors only)",
                    what.c_str(), texture_index));
      return ref;
    }
    if (static_cast<size_t>(image) >= model_.images.size()) {
      return invalid_argument(
          strprintf("%s: texture %d: source image %d does not exist (%zu images)", what.c_str(),
                    texture_index, image, model_.images.size()));
    }
    ref.texcoord = texcoord;
    LUXEL_RETURN_IF_ERROR(read_sampler(texture_index, what, &ref));
    LUXEL_RETURN_IF_ERROR(read_transform(ext, what, &ref));
    for (const auto& [name, value] : ext)
      if (name != "KHR_texture_transform")
        warnings().push_back(what + ": texture extension " + name + " is not supported (ignored)");
    const auto key = std::make_pair(image, space);
    auto it = decoded_.find(key);
    if (it == decoded_.end()) {
      auto tex = decode_texture(model_, image, space, options_, &pixel_budget_);
      if (!tex) return Status(tex.status().code(), what + ": " + tex.status().message());
      scene_->textures.push_back(std::move(*tex));
      it = decoded_.emplace(key, static_cast<int>(scene_->textures.size() - 1)).first;
    }
    ref.texture = it->second;
    return ref;
  }

 private:
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

  auto base = table->resolve(pbr.baseColorTexture, ColorSpace::kSRGB, label + " baseColorTexture");
  if (!base) return base.status();
  m.base_color_texture = *base;
  auto mr = table->resolve(pbr.metallicRoughnessTexture, ColorSpace::kLinear,
                           label + " metallicRoughnessTexture");
  if (!mr) return mr.status();
  m.metallic_roughness_texture = *mr;
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
         name == "KHR_materials_specular";
}

Status convert_materials(const tinygltf::Model& model, const ImportOptions& options, Scene* scene) {
  TextureTable table(model, options, scene);
  for (size_t i = 0; i < model.materials.size(); ++i) {
    auto m = convert(model, static_cast<int>(i), &table);
    if (!m) return m.status();
    scene->materials.push_back(std::move(*m));
  }
  return Status::ok();
}

}  // namespace luxel::scene::detail
