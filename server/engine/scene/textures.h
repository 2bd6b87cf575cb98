// Image decoding: encoded PNG/JPEG (8 or 16 bit, 1-4 channels) -> linear
// float RGBA. Sizes are checked (stbi_info) before any pixel is allocated.
#pragma once

#include <cstdint>

#include "common/status.h"
#include "scene/gltf_import.h"
#include "scene/scene.h"
#include "scene/tinygltf_config.h"

namespace luxel::scene::detail {

// The exact sRGB EOTF (IEC 61966-2-1), value in [0,1].
float srgb_to_linear(float encoded);

// "image 3 'bricks'" / "image 3" for messages.
std::string image_label(const tinygltf::Model& model, int image);

// Decodes glTF image `image`. Colour channels are linearized when `space` is
// kSRGB; alpha is always linear. With options.decode_textures false only the
// size is read. `pixel_budget` is decremented by the decoded pixel count.
Result<Texture> decode_texture(const tinygltf::Model& model, int image, ColorSpace space,
                               const ImportOptions& options, uint64_t* pixel_budget);

}  // namespace luxel::scene::detail
