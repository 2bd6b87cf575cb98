// glTF 2.0 import (.gltf with external or embedded buffers, .glb) via tinygltf.
//
// Validates everything a later stage relies on and fails with an error that
// names the node / mesh / primitive / accessor at fault. A malformed file never
// crashes the process (fuzzed by tests/fuzz/import_fuzz.cpp).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "common/status.h"
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
};

// Loads a file from disk; the format is chosen by content (glb magic) and not
// by extension. External buffers/images resolve relative to the file.
Result<Scene> import_gltf_file(const std::string& path, const ImportOptions& options = {});

// Loads from memory. base_dir resolves external URIs ("" forbids external
// files, as for uploads that did not include them). name is used in messages.
Result<Scene> import_gltf_memory(std::string_view bytes, const std::string& base_dir,
                                 const std::string& name, const ImportOptions& options = {});

}  // namespace luxel::scene
