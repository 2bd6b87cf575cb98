#include "pipeline/shading/texture_pack.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "pipeline/shading/color.h"

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
  uint64_t total = 0;
  for (size_t i = 0; i < scene.textures.size(); ++i) {
    const scene::Texture& t = scene.textures[i];
    const uint64_t n = uint64_t(std::max(t.width, 0)) * uint64_t(std::max(t.height, 0));
    if (n == 0 || t.rgba.size() != n * 4)
      return invalid_argument(
          strprintf("texture %zu '%s': %d x %d with %zu values has no usable pixels "
                    "(imported without decoding?)",
                    i, t.name.c_str(), t.width, t.height, t.rgba.size()));
    total += n;
  }
  if (total > uint64_t(std::numeric_limits<int32_t>::max()))
    return resource_exhausted(
        strprintf("the scene's %zu textures hold %llu texels; at most %d fit the device "
                  "texel index",
                  scene.textures.size(), static_cast<unsigned long long>(total),
                  std::numeric_limits<int32_t>::max()));

  pack.texels.reserve(total);
  for (const scene::Texture& t : scene.textures) {
    const bool srgb = t.source_space == scene::ColorSpace::kSRGB;
    cl::LuxTexture lt{};
    lt.offset = static_cast<int>(pack.texels.size());
    lt.width = t.width;
    lt.height = t.height;
    lt.flags = srgb ? LUX_TEXTURE_FLAG_SRGB : 0;
    pack.textures.push_back(lt);
    auto colour = srgb ? encode_srgb8 : encode_linear8;
    const size_t n = t.rgba.size() / 4;
    for (size_t k = 0; k < n; ++k) {
      const float* p = &t.rgba[k * 4];
      pack.texels.push_back(
          pack_rgba(colour(p[0]), colour(p[1]), colour(p[2]), encode_linear8(p[3])));
    }
  }
  return pack;
}

}  // namespace luxel::pipeline
