// Material textures packed for the device (kernels/shared/texture.h): one
// shared uint buffer holding each texture in its host format, copied as is:
// 8-bit textures as RGBA8 words (colour textures keep the file's sRGB codes,
// decoded exactly on fetch by kernels/shading/texture.h), 16-bit textures as
// linear RGBA halves (two words per texel). 4 or 8 bytes per texel, the same
// as the host copy (scene::Texture).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/status.h"
#include "kernels/shared/texture.h"
#include "scene/scene.h"

namespace luxel::pipeline {

struct TexturePack {
  std::vector<cl::LuxTexture> textures;  // one per scene::Scene::textures, same index
  std::vector<uint32_t> texels;          // RGBA8 (R in the low byte) or 2 words of halves
  size_t bytes() const;
};

// Packs every scene texture.
// Errors: a texture without pixels (imported with decoding off) or whose
// pixel count does not match its size -> INVALID_ARGUMENT naming it; more
// than 2^31 texels in all -> RESOURCE_EXHAUSTED.
Result<TexturePack> pack_textures(const scene::Scene& scene);

// The 8-bit code of a linear value in [0, 1] (clamped) under each encoding;
// exposed for tests and for writers that must match the device.
uint8_t encode_srgb8(float linear);
uint8_t encode_linear8(float linear);

}  // namespace luxel::pipeline
