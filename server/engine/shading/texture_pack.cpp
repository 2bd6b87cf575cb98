#include "shading/texture_pack.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "shading/color.h"

namespace luxel::pipeline {
namespace {

float clamp01(float v) {
  return v > 0 ? std::min(v, 1.0f) : 0.0f;
}  // also NaN -> 0

uint32_t pack_rgba(uint8_t r, uint8_t g, uint8_t b, uint8_t a) {
  return uint32_t{r} | (uint32_t{g} << 8) | (uint32_t{b} << 16) | (uint32_t{a} << 24);
}

}  // namespace

uint8_t encode_srgb8(float linear) {
  return static_cast<uint8_t>(std::lround(linear_to_srgb(clamp01(linear)) * 255.0f));
}

uint8_t encode_linear8(float linear) {
  return static_cast<uint8_t>(std::lround(clamp01(linear) * 255.0f));
}

size_t TexturePack::bytes() const {
  return textures.size() * sizeof(cl::LuxTexture) + texels.size() * sizeof(uint32_t);
}

Result<TexturePack> pack_textures(const scene::Scene& scene) {
  TexturePack pack;
  uint64_t total = 0;  // uint words
  for (size_t i = 0; i < scene.textures.size(); ++i) {
    const scene::Texture& t = scene.textures[i];
    if (!t.has_pixels())
      return invalid_argument(
          strprintf("texture %zu '%s': %d x %d with %zu values has no usable pixels "
                    "(imported without decoding?)",
                    i, t.name.c_str(), t.width, t.height, t.rgba8.size() + t.rgba16f.size()));
    total += uint64_t(t.texel_count()) * (t.format == scene::TexelFormat::kRGBA16F ? 2 : 1);
  }
  if (total > uint64_t(std::numeric_limits<int32_t>::max()))
    return resource_exhausted(
        strprintf("the scene's %zu textures hold %llu texel words; at most %d fit the device "
                  "texel index",
                  scene.textures.size(), static_cast<unsigned long long>(total),
                  std::numeric_limits<int32_t>::max()));

  pack.texels.reserve(total);
  for (const scene::Texture& t : scene.textures) {
    cl::LuxTexture lt{};
    lt.offset = static_cast<int>(pack.texels.size());
    lt.width = t.width;
    lt.height = t.height;
    const size_t n = t.texel_count();
    if (t.format == scene::TexelFormat::kRGBA16F) {
      // Four halves in two words, in memory order (vload_half4 reads them so).
      lt.flags = LUX_TEXTURE_FLAG_HALF;
      const size_t first = pack.texels.size();
      pack.texels.resize(first + n * 2);
      std::memcpy(&pack.texels[first], t.rgba16f.data(), n * 4 * sizeof(uint16_t));
    } else {
      // The file's codes as they are: sRGB colour is decoded on fetch.
      lt.flags = t.source_space == scene::ColorSpace::kSRGB ? LUX_TEXTURE_FLAG_SRGB : 0;
      for (size_t k = 0; k < n; ++k) {
        const uint8_t* p = &t.rgba8[k * 4];
        pack.texels.push_back(pack_rgba(p[0], p[1], p[2], p[3]));
      }
    }
    pack.textures.push_back(lt);
  }
  return pack;
}

}  // namespace luxel::pipeline
