// glTF 2.0 import (.gltf with external or embedded buffers, .glb) via tinygltf.
//
// Validates everything a later stage relies on and fails with an error that
// names the node / mesh / primitive / accessor at fault. A malformed file never
// crashes the process (fuzzed by tests/fuzz/import_fuzz.cpp).
//
// Materials are glTF 2.0 metallic-roughness; other material models are
// turned into it here, so the bake has one BRDF (docs/accuracy.md):
// - KHR_materials_unlit: an unlit surface has no BRDF, but in a lightmap bake
//   it still occludes and still gets its own texels baked; light that
//   reaches it bounces as its base colour says. It becomes a Lambertian
//   diffuse surface of albedo base colour (factor times texture, alpha and
//   doubleSided as in the file), metallic 0, no specular layer
//   (specular_factor 0) and no emission; the core's other inputs are the
//   file's fallback and are not read.
// - KHR_materials_pbrSpecularGlossiness: converted to metallic-roughness
//   (scene/spec_gloss.h), textures per texel into new textures.
// - KHR_texture_basisu: KTX2 images are not decoded; a texture's PNG/JPEG
//   fallback `source` is used, a texture without one is an error naming it,
//   and the extension in extensionsRequired is refused.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "common/status.h"
#include "scene/import_budget.h"
#include "scene/scene.h"

namespace luxel::scene {

struct ImportOptions {
  // Refuse a primitive without TEXCOORD_1. Off by default: the bake generates
  // lightmap UVs for meshes without them (Mesh::has_lightmap_uvs).
  bool require_lightmap_uvs = false;
  // Decode textures (false: materials keep texture references, Scene::textures
  // have names and sizes but empty pixel data). Used by tools that only count.
  bool decode_textures = true;

  // Resource limits, checked before memory is allocated, so that a small
  // malicious file cannot claim gigabytes (a count or an image size is only a
  // number in the file). Exceeding one is kResourceExhausted.
  // Decoded accessor elements over the whole import (vertices + indices).
  uint64_t max_accessor_elements = uint64_t{1} << 30;
  // Per image: longest side and pixel count; over all images: decoded pixels.
  int max_image_side = 16384;
  uint64_t max_image_pixels = uint64_t{1} << 26;          // 8192 x 8192
  uint64_t max_total_texture_pixels = uint64_t{1} << 28;  // 4 GiB of float RGBA

  // Bytes the import may allocate (scene/import_budget.h): vertices, indices,
  // instances and decoded texels, charged from declared counts before they
  // are allocated. With `memory_pool` set, the import reserves from that
  // shared pool (the daemon's, over all concurrent imports) and
  // max_import_bytes is not used.
  uint64_t max_import_bytes = default_import_memory_budget();
  ImportMemoryPool* memory_pool = nullptr;
  // Seconds the import may run (checked inside its loops); past it the
  // import ends with kDeadlineExceeded. Values <= 0 end it at the first check.
  double timeout_seconds = 300;
};

// Loads a file from disk; the format is chosen by content (glb magic) and not
// by extension. External buffers/images resolve relative to the file.
Result<Scene> import_gltf_file(const std::string& path, const ImportOptions& options = {});

// Loads from memory. base_dir resolves external URIs ("" forbids external
// files, as for uploads that did not include them). name is used in messages.
Result<Scene> import_gltf_memory(std::string_view bytes, const std::string& base_dir,
                                 const std::string& name, const ImportOptions& options = {});

}  // namespace luxel::scene
