// Image decoding: encoded PNG/JPEG (8 or 16 bit, 1-4 channels) -> RGBA8
// codes (8-bit images) or linear RGBA halves (16-bit images). Sizes are checked (stbi_info) before
// any pixel is allocated.
#pragma once

#include <cstdint>

#include "common/status.h"
#include "scene/gltf_import.h"
#include "scene/import_budget.h"
#include "scene/scene.h"
#include "scene/tinygltf_config.h"

namespace luxel::scene::detail {

// The exact sRGB EOTF (IEC 61966-2-1), value in [0,1].
float srgb_to_linear(float encoded);
// srgb_to_linear(code / 255), tabulated.
float srgb8_to_linear(uint8_t code);

// "image 3 'bricks'" / "image 3" for messages.
std::string image_label(const tinygltf::Model& model, int image);

// The bytes decoding image `image` keeps (4 per texel, 8 for 16-bit
// images) from its header alone; 0 when the image has no data or no header
// stb_image reads or over the per-image limits (decode_texture reports
// those). `w`, `h`: the header's size.
uint64_t declared_texel_bytes(const tinygltf::Model& model, int image, const ImportOptions& options,
                              int* w, int* h);

// Decodes glTF image `image`. 8-bit images keep their codes; 16-bit images
// are linearized (colour channels through the sRGB EOTF when `space` is
// kSRGB; alpha is always linear) and stored as halves. With options.decode_textures false only the
// size is read. `pixel_budget` is decremented by the decoded pixel count;
// the texels are reserved in `budget` before stb_image allocates them (the
// decoder's own buffers only while it runs).
Result<Texture> decode_texture(const tinygltf::Model& model, int image, ColorSpace space,
                               const ImportOptions& options, uint64_t* pixel_budget,
                               ImportBudget* budget);

}  // namespace luxel::scene::detail
