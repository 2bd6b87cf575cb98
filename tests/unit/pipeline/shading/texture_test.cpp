// Texture packing (RGBA8, sRGB or linear) and lux_texture_sample on the
// device: bilinear filtering and repeat wrapping against a host reference,
// sRGB round trip within one 8-bit step.
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "pipeline/shading/color.h"
#include "pipeline/shading/texture_pack.h"
#include "shading_probe.h"
#include "test_scenes.h"

namespace luxel::pipeline {
namespace {

using test::Rng;

scene::Texture make_texture(const std::string& name, int w, int h, scene::ColorSpace space,
                            Rng& rng) {
  scene::Texture t;
  t.name = name;
  t.width = w;
  t.height = h;
  t.source_space = space;
  t.rgba.resize(size_t(w) * size_t(h) * 4);
  for (float& v : t.rgba) v = rng.uniform();
  return t;
}

// Host reference: decode the packed texel (exact sRGB formula), then
// bilinear with repeat wrap, texel centres at (x + 0.5) / w, row 0 = v 0.
std::array<double, 4> reference_sample(const TexturePack& pack, int index, double u, double v) {
  const cl::LuxTexture& t = pack.textures[size_t(index)];
  auto texel = [&](int x, int y) {
    x = ((x % t.width) + t.width) % t.width;
    y = ((y % t.height) + t.height) % t.height;
    const uint32_t w = pack.texels[size_t(t.offset) + size_t(y) * size_t(t.width) + size_t(x)];
    std::array<double, 4> c;
    for (int k = 0; k < 4; ++k) {
      const double e = ((w >> (8 * k)) & 0xff) / 255.0;
      c[size_t(k)] = (k < 3 && (t.flags & LUX_TEXTURE_FLAG_SRGB))
                         ? (e <= 0.04045 ? e / 12.92 : std::pow((e + 0.055) / 1.055, 2.4))
                         : e;
    }
    return c;
  };
  const double x = u * t.width - 0.5, y = v * t.height - 0.5;
  const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
  const double fx = x - x0, fy = y - y0;
  std::array<double, 4> r{};
  const auto a = texel(x0, y0), b = texel(x0 + 1, y0), c = texel(x0, y0 + 1),
             d = texel(x0 + 1, y0 + 1);
  for (size_t k = 0; k < 4; ++k)
    r[k] = (1 - fy) * ((1 - fx) * a[k] + fx * b[k]) + fy * ((1 - fx) * c[k] + fx * d[k]);
  return r;
}

TEST(TexturePack, PacksRgba8WithSrgbFlagsAndOffsets) {
  Rng rng(31);
  scene::Scene s;
  s.textures.push_back(make_texture("albedo", 5, 3, scene::ColorSpace::kSRGB, rng));
  s.textures.push_back(make_texture("roughness", 4, 7, scene::ColorSpace::kLinear, rng));
  auto pack = pack_textures(s);
  ASSERT_TRUE(pack.is_ok()) << pack.status().to_string();
  ASSERT_EQ(pack->textures.size(), 2u);
  EXPECT_EQ(pack->textures[0].flags, LUX_TEXTURE_FLAG_SRGB);
  EXPECT_EQ(pack->textures[1].flags, 0);
  EXPECT_EQ(pack->textures[1].offset, 15);
  EXPECT_EQ(pack->texels.size(), 15u + 28u);
  EXPECT_EQ(pack->bytes(), 43u * 4 + 2 * sizeof(cl::LuxTexture));
  // R in the low byte, alpha (linear) in the high byte.
  const float* p = &s.textures[1].rgba[0];
  EXPECT_EQ(pack->texels[15], uint32_t(encode_linear8(p[0])) | uint32_t(encode_linear8(p[1])) << 8 |
                                  uint32_t(encode_linear8(p[2])) << 16 |
                                  uint32_t(encode_linear8(p[3])) << 24);
  EXPECT_EQ(pack->texels[0] >> 24, encode_linear8(s.textures[0].rgba[3]));
  EXPECT_EQ(encode_srgb8(NAN), 0);
  EXPECT_EQ(encode_srgb8(7.0f), 255);

  scene::Scene undecoded;
  undecoded.textures.push_back(scene::Texture{});
  undecoded.textures.back().name = "lazy.png";
  undecoded.textures.back().width = 4;
  undecoded.textures.back().height = 4;
  auto err = pack_textures(undecoded);
  ASSERT_FALSE(err.is_ok());
  EXPECT_EQ(err.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(err.status().message().find("lazy.png"), std::string::npos) << err.status().to_string();
}

TEST(TextureSample, BilinearWithRepeatWrapMatchesTheHostReference) {
  Rng rng(32);
  scene::Scene s;
  s.textures.push_back(make_texture("albedo", 5, 3, scene::ColorSpace::kSRGB, rng));
  s.textures.push_back(make_texture("data", 4, 7, scene::ColorSpace::kLinear, rng));
  auto pack = pack_textures(s);
  ASSERT_TRUE(pack.is_ok());
  std::vector<cl::float2> uv;
  for (int i = 0; i < 2000; ++i)
    uv.push_back({rng.uniform() * 6 - 3, rng.uniform() * 6 - 3});  // wraps both ways
  uv.push_back({0, 0});            // corner: mixes the four corner texels
  uv.push_back({0.1f, 1.0f / 6});  // texel centre (0, 0) of the 5 x 3 texture
  uv.push_back({1e6f + 0.25f, -0.75f});
  for (int tex = 0; tex < 2; ++tex) {
    auto out = test::probe_texture(pack.value(), tex, uv);
    ASSERT_TRUE(out.is_ok()) << out.status().to_string();
    for (size_t i = 0; i < uv.size(); ++i) {
      // The device wraps uv before scaling (uv - floor(uv)); so does the reference.
      const double u = uv[i].x - std::floor(double(uv[i].x)),
                   v = uv[i].y - std::floor(double(uv[i].y));
      const auto ref = reference_sample(pack.value(), tex, u, v);
      const float got[4] = {(*out)[i].x, (*out)[i].y, (*out)[i].z, (*out)[i].w};
      for (size_t k = 0; k < 4; ++k)
        ASSERT_NEAR(got[k], ref[k], 2e-5)
            << "texture " << tex << " uv (" << uv[i].x << ", " << uv[i].y << ") channel " << k;
    }
  }
  // The texel centre returns the texel itself.
  auto centre = test::probe_texture(pack.value(), 0, {{0.1f, 1.0f / 6}});
  ASSERT_TRUE(centre.is_ok());
  const uint32_t w = pack->texels[0];
  EXPECT_NEAR((*centre)[0].x, srgb_to_linear((w & 0xff) / 255.0f), 1e-6);
}

TEST(TextureSample, SrgbRoundTripStaysWithinOneStep) {
  Rng rng(33);
  scene::Texture t;
  t.name = "ramp";
  t.source_space = scene::ColorSpace::kSRGB;
  t.width = 256;
  t.height = 2;
  // Row 0: every 8-bit sRGB level, decoded to linear as the importer does.
  // Row 1: arbitrary linear values.
  for (int row = 0; row < 2; ++row)
    for (int x = 0; x < 256; ++x) {
      const float lin = row == 0 ? srgb_to_linear(x / 255.0f) : rng.uniform();
      t.rgba.insert(t.rgba.end(), {lin, lin, lin, x / 255.0f});
    }
  scene::Texture data = t;
  data.name = "linear ramp";
  data.source_space = scene::ColorSpace::kLinear;
  scene::Scene s;
  s.textures = {t, data};
  auto pack = pack_textures(s);
  ASSERT_TRUE(pack.is_ok());
  std::vector<cl::float2> uv;
  for (int row = 0; row < 2; ++row)
    for (int x = 0; x < 256; ++x) uv.push_back({(x + 0.5f) / 256, (row + 0.5f) / 2});
  auto srgb = test::probe_texture(pack.value(), 0, uv);
  auto linear = test::probe_texture(pack.value(), 1, uv);
  ASSERT_TRUE(srgb.is_ok() && linear.is_ok());
  double worst_srgb = 0, worst_linear = 0;
  for (size_t i = 0; i < uv.size(); ++i) {
    const float original = t.rgba[i * 4];
    worst_srgb = std::max(
        worst_srgb, double(std::fabs(linear_to_srgb((*srgb)[i].x) - linear_to_srgb(original))));
    worst_linear = std::max(worst_linear, double(std::fabs((*linear)[i].x - original)));
    ASSERT_NEAR((*srgb)[i].w, t.rgba[i * 4 + 3], 0.5 / 255 + 1e-6) << "alpha stays linear";
  }
  EXPECT_LT(worst_srgb, 1.0 / 255) << "sRGB-space error of the sRGB-encoded texture";
  EXPECT_LT(worst_srgb, 0.5 / 255 + 1e-5) << "at most half a step: encoding rounds to nearest";
  EXPECT_LT(worst_linear, 0.5 / 255 + 1e-6);
}

}  // namespace
}  // namespace luxel::pipeline
