// See textures.h. stb_image is linked from libstb; tinygltf's own decoder is
// disabled (tinygltf_config.h) because it decodes before we can check sizes.
#include "scene/textures.h"

#include <stb_image.h>

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <cstring>
#include <memory>

#include "common/half.h"
#include "scene/accessor.h"

namespace luxel::scene::detail {
namespace {

struct StbFree {
  void operator()(void* p) const { stbi_image_free(p); }
};

const std::array<float, 256>& srgb_lut() {
  static const std::array<float, 256> lut = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i)
      t[static_cast<size_t>(i)] = srgb_to_linear(static_cast<float>(i) / 255.0f);
    return t;
  }();
  return lut;
}

uint32_t be16(const uint8_t* p) {
  return (uint32_t{p[0]} << 8) | p[1];
}

uint32_t be32(const uint8_t* p) {
  return (be16(p) << 16) | be16(p + 2);
}

// The size a PNG (IHDR) or JPEG (SOFn) header claims, read without stb_image:
// stbi_info refuses a header whose image it would not decode (over 2^30
// bytes) and then reports only "unknown image type".
bool header_size(const uint8_t* p, size_t n, uint64_t* w, uint64_t* h) {
  static const uint8_t kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (n >= 24 && std::memcmp(p, kPng, 8) == 0 && std::memcmp(p + 12, "IHDR", 4) == 0) {
    *w = be32(p + 16);
    *h = be32(p + 20);
    return true;
  }
  if (n < 4 || p[0] != 0xFF || p[1] != 0xD8) return false;
  size_t at = 2;
  while (at + 4 <= n && p[at] == 0xFF) {
    const uint8_t marker = p[at + 1];
    if (marker == 0xFF) {  // fill byte
      ++at;
      continue;
    }
    const size_t length = be16(p + at + 2);
    const bool sof =
        marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (sof) {
      if (at + 9 > n) return false;
      *h = be16(p + at + 5);
      *w = be16(p + at + 7);
      return true;
    }
    if (length < 2) return false;
    at += 2 + length;
  }
  return false;
}

}  // namespace

float srgb8_to_linear(uint8_t code) {
  return srgb_lut()[code];
}

float srgb_to_linear(float c) {
  const double v = static_cast<double>(c);
  return static_cast<float>(v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4));
}

std::string image_label(const tinygltf::Model& model, int image) {
  const auto& img = model.images[static_cast<size_t>(image)];
  const std::string& n =
      !img.name.empty() ? img.name : (img.uri.rfind("data:", 0) == 0 ? std::string() : img.uri);
  return n.empty() ? strprintf("image %d", image) : strprintf("image %d '%s'", image, n.c_str());
}

uint64_t declared_texel_bytes(const tinygltf::Model& model, int image, const ImportOptions& options,
                              int* w, int* h) {
  if (image < 0 || static_cast<size_t>(image) >= model.images.size()) return 0;
  const auto& img = model.images[static_cast<size_t>(image)];
  std::string_view encoded;
  if (img.bufferView >= 0) {
    auto bytes = buffer_view_bytes(model, img.bufferView, "");
    if (!bytes) return 0;
    encoded = *bytes;
  } else {
    encoded = std::string_view(reinterpret_cast<const char*>(img.image.data()), img.image.size());
  }
  if (encoded.empty() || encoded.size() > static_cast<size_t>(INT_MAX)) return 0;
  const auto* data = reinterpret_cast<const stbi_uc*>(encoded.data());
  const int size = static_cast<int>(encoded.size());
  int channels = 0;
  if (!stbi_info_from_memory(data, size, w, h, &channels) || *w <= 0 || *h <= 0 ||
      *w > options.max_image_side || *h > options.max_image_side)
    return 0;
  const uint64_t pixels = static_cast<uint64_t>(*w) * static_cast<uint64_t>(*h);
  if (pixels > options.max_image_pixels) return 0;
  return mul_sat(pixels, 4, stbi_is_16_bit_from_memory(data, size) ? 2 : 1);
}

Result<Texture> decode_texture(const tinygltf::Model& model, int image, ColorSpace space,
                               const ImportOptions& options, uint64_t* pixel_budget,
                               ImportBudget* budget) {
  const auto& img = model.images[static_cast<size_t>(image)];
  const std::string label = image_label(model, image);
  std::string_view encoded;
  if (img.bufferView >= 0) {
    auto bytes = buffer_view_bytes(model, img.bufferView, label);
    if (!bytes) return bytes.status();
    encoded = *bytes;
  } else if (!img.image.empty()) {
    encoded = std::string_view(reinterpret_cast<const char*>(img.image.data()), img.image.size());
  } else if (!img.uri.empty() && img.uri.rfind("data:", 0) != 0) {
    return not_found(
        strprintf("%s: file '%s' could not be loaded", label.c_str(), img.uri.c_str()));
  } else {
    return invalid_argument(label + ": has neither image data nor a bufferView");
  }
  if (encoded.empty() || encoded.size() > static_cast<size_t>(INT_MAX)) {
    return invalid_argument(
        strprintf("%s: %zu bytes of encoded data", label.c_str(), encoded.size()));
  }
  const auto* data = reinterpret_cast<const stbi_uc*>(encoded.data());
  const int size = static_cast<int>(encoded.size());
  const auto too_large = [&](uint64_t w, uint64_t h) {
    return resource_exhausted(strprintf(
        "%s: %llu x %llu pixels is too large (the limit is %d per side and %llu pixels)",
        label.c_str(), static_cast<unsigned long long>(w), static_cast<unsigned long long>(h),
        options.max_image_side, static_cast<unsigned long long>(options.max_image_pixels)));
  };
  int w = 0, h = 0, channels = 0;
  if (!stbi_info_from_memory(data, size, &w, &h, &channels)) {
    uint64_t hw = 0, hh = 0;
    if (header_size(data, encoded.size(), &hw, &hh) &&
        (hw > static_cast<uint64_t>(options.max_image_side) ||
         hh > static_cast<uint64_t>(options.max_image_side) ||
         hw * hh > options.max_image_pixels)) {
      return too_large(hw, hh);
    }
    return invalid_argument(
        strprintf("%s: cannot decode the image: %s", label.c_str(), stbi_failure_reason()));
  }
  const uint64_t pixels = static_cast<uint64_t>(w) * static_cast<uint64_t>(h);
  if (w <= 0 || h <= 0 || w > options.max_image_side || h > options.max_image_side ||
      pixels > options.max_image_pixels) {
    return too_large(static_cast<uint64_t>(w), static_cast<uint64_t>(h));
  }
  Texture tex;
  tex.name = !img.name.empty()                                     ? img.name
             : (img.uri.empty() || img.uri.rfind("data:", 0) == 0) ? strprintf("image[%d]", image)
                                                                   : img.uri;
  tex.gltf_image = image;
  tex.source_space = space;
  tex.width = w;
  tex.height = h;
  if (!options.decode_textures) return tex;
  if (pixels > *pixel_budget) {
    return resource_exhausted(strprintf(
        "%s: decoding %d x %d pixels exceeds the import's texture budget", label.c_str(), w, h));
  }
  *pixel_budget -= pixels;
  LUXEL_RETURN_IF_ERROR(budget->check_deadline(label));
  // Reserved before stb_image allocates: the kept RGBA (4 bytes per texel,
  // 8 for 16-bit images) for the import, and stb_image's buffers for the
  // decode (its inflated rows and the unfiltered image, `channels` samples
  // per texel each, and its RGBA output).
  const bool is16 = stbi_is_16_bit_from_memory(data, size) != 0;
  const uint64_t sample = is16 ? 2 : 1;
  const std::string what = strprintf("%s: %d x %d texels (%s, %d channel%s)", label.c_str(), w, h,
                                     is16 ? "16-bit" : "8-bit", channels, channels == 1 ? "" : "s");
  const uint64_t kept = mul_sat(pixels, 4 * sample);
  const uint64_t transient =
      mul_sat(pixels, sample, 2 * static_cast<uint64_t>(std::max(channels, 1)) + 4);
  LUXEL_RETURN_IF_ERROR(budget->reserve(add_sat(kept, transient), what));
  ScopedReservation decoding(budget);
  decoding.adopt(transient);

  const bool srgb = space == ColorSpace::kSRGB;
  int dw = 0, dh = 0, dc = 0;
  if (is16) {
    // 16 bits carry more than 8-bit codes can keep: linear halves (11
    // significant bits, relative error <= 2^-11, finer than the 8-bit step
    // wherever the value is above ~0.06).
    std::unique_ptr<stbi_us, StbFree> px(stbi_load_16_from_memory(data, size, &dw, &dh, &dc, 4));
    if (!px || dw != w || dh != h) {
      return invalid_argument(
          strprintf("%s: cannot decode the image: %s", label.c_str(), stbi_failure_reason()));
    }
    tex.format = TexelFormat::kRGBA16F;
    tex.rgba16f.resize(pixels * 4);
    for (uint64_t i = 0; i < pixels * 4; ++i) {
      const float v = static_cast<float>(px.get()[i]) / 65535.0f;
      tex.rgba16f[i] = float_to_half((srgb && i % 4 != 3) ? srgb_to_linear(v) : v);
    }
  } else {
    std::unique_ptr<stbi_uc, StbFree> px(stbi_load_from_memory(data, size, &dw, &dh, &dc, 4));
    if (!px || dw != w || dh != h) {
      return invalid_argument(
          strprintf("%s: cannot decode the image: %s", label.c_str(), stbi_failure_reason()));
    }
    tex.format = TexelFormat::kRGBA8;
    tex.rgba8.assign(px.get(), px.get() + pixels * 4);
  }
  return tex;
}

}  // namespace luxel::scene::detail

namespace luxel::scene {

Vec4 Texture::linear(size_t i) const {
  if (format == TexelFormat::kRGBA16F) {
    const uint16_t* p = &rgba16f[i * 4];
    return {half_to_float(p[0]), half_to_float(p[1]), half_to_float(p[2]), half_to_float(p[3])};
  }
  const uint8_t* p = &rgba8[i * 4];
  const float a = static_cast<float>(p[3]) / 255.0f;
  if (source_space == ColorSpace::kSRGB)
    return {detail::srgb8_to_linear(p[0]), detail::srgb8_to_linear(p[1]),
            detail::srgb8_to_linear(p[2]), a};
  return {static_cast<float>(p[0]) / 255.0f, static_cast<float>(p[1]) / 255.0f,
          static_cast<float>(p[2]) / 255.0f, a};
}

}  // namespace luxel::scene
