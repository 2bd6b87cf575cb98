// Material textures packed for the device: RGBA8 in one shared buffer
// (kernels/shared/texture.h). Colour textures whose file was sRGB are
// re-encoded as sRGB 8-bit (decoded exactly on fetch by
// kernels/shading/texture.h), data textures as linear 8-bit: 4 bytes per
// texel instead of the 16 of the scene's float RGBA, with at most half an
// 8-bit step of error in the file's own encoding.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/status.h"
#include "scene/scene.h"
#include "shared/texture.h"

namespace luxel::pipeline {

struct TexturePack {
  std::vector<cl::LuxTexture> textures;  // one per scene::Scene::textures, same index
  std::vector<uint32_t> texels;          // RGBA8, R in the low byte
  size_t bytes() const;
};

// Packs every scene texture. Values are clamped to [0, 1] (NaN -> 0).
// Errors: a texture without pixels (imported with decoding off) or whose
// pixel count does not match its size -> INVALID_ARGUMENT naming it; more
// than 2^31 texels in all -> RESOURCE_EXHAUSTED.
Result<TexturePack> pack_textures(const scene::Scene& scene);

// The 8-bit code of a linear value in [0, 1] (clamped) under each encoding;
// exposed for tests and for writers that must match the device.
uint8_t encode_srgb8(float linear);
uint8_t encode_linear8(float linear);

}  // namespace luxel::pipeline
