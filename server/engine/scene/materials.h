// glTF materials -> scene::Material (same indices) and the textures they use.
#pragma once

#include <string>

#include "common/status.h"
#include "scene/gltf_import.h"
#include "scene/scene.h"
#include "scene/tinygltf_config.h"

namespace luxel::scene::detail {

// Appends one Material per glTF material to scene->materials (so glTF
// material i is Scene material i) and decodes each (image, colour space) pair
// they reference once into scene->textures, their texels reserved in
// `budget` (scene/import_budget.h) before they are decoded.
Status convert_materials(const tinygltf::Model& model, const ImportOptions& options,
                         ImportBudget* budget, Scene* scene);

// Whether the importer reads glTF extension `name` (KHR_lights_punctual,
// KHR_materials_emissive_strength, KHR_materials_ior, KHR_texture_transform,
// KHR_materials_specular, KHR_materials_unlit (baked as a Lambertian surface
// of albedo base colour, see materials.cpp), KHR_materials_pbrSpecularGlossiness
// (converted to metallic-roughness, spec_gloss.h), KHR_texture_basisu (its
// PNG/JPEG fallback source is used; a texture without one is an error, and
// gltf_import.cpp refuses the extension in extensionsRequired)); the others
// are named in the import warnings.
bool is_supported_extension(const std::string& name);

}  // namespace luxel::scene::detail
