// Texture packing (the host's RGBA8 codes or halves, copied as is) and
// lux_texture_slot_sample on the device: sRGB decode against the closed-form
// EOTF at every 8-bit code, halves through vload_half, bilinear filtering
// under each glTF wrap mode against OpenGL's Table 8.20, KHR_texture_transform
// against the extension's T * R * S, and the UV set a slot selects.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <functional>

#include "common/half.h"
#include "shading/texture_pack.h"
#include "shading_probe.h"
#include "test_scenes.h"

namespace luxel::pipeline {
namespace {

using test::Rng;

scene::Texture make_texture(const std::string& name, int w, int h, scene::ColorSpace space,
                            Rng& rng, bool half = false) {
  scene::Texture t;
  t.name = name;
  t.width = w;
  t.height = h;
  t.source_space = space;
  const size_t n = size_t(w) * size_t(h) * 4;
  if (half) {
    t.format = scene::TexelFormat::kRGBA16F;
    for (size_t i = 0; i < n; ++i) t.rgba16f.push_back(float_to_half(rng.uniform() * 4));
  } else {
    for (size_t i = 0; i < n; ++i) t.rgba8.push_back(uint8_t(rng.uniform() * 255.99f));
  }
  return t;
}

double srgb_eotf(double e) {
  return e <= 0.04045 ? e / 12.92 : std::pow((e + 0.055) / 1.055, 2.4);
}

// Integer texel index under a wrap mode, OpenGL 4.6 Table 8.20.
int wrap_index(int i, int n, int mode) {
  auto mod = [](int a, int m) { return ((a % m) + m) % m; };
  if (mode == LUX_WRAP_CLAMP) return std::clamp(i, 0, n - 1);
  if (mode == LUX_WRAP_MIRROR) {
    const int a = mod(i, 2 * n) - n;
    return (n - 1) - (a >= 0 ? a : -(1 + a));
  }
  return mod(i, n);
}

// Host reference: the scene texture's linear texels (exact sRGB formula or
// the half), bilinear at (u, v) unreduced, integer indices wrapped.
std::array<double, 4> reference_sample(const scene::Texture& t, double u, double v, int ws = 0,
                                       int wt = 0) {
  auto texel = [&](int x, int y) {
    x = wrap_index(x, t.width, ws);
    y = wrap_index(y, t.height, wt);
    const size_t i = size_t(y) * size_t(t.width) + size_t(x);
    std::array<double, 4> c;
    for (size_t k = 0; k < 4; ++k) {
      if (t.format == scene::TexelFormat::kRGBA16F) {
        c[k] = half_to_float(t.rgba16f[i * 4 + k]);
      } else {
        const double e = t.rgba8[i * 4 + k] / 255.0;
        c[k] = (k < 3 && t.source_space == scene::ColorSpace::kSRGB) ? srgb_eotf(e) : e;
      }
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

cl::LuxTextureSlot identity_slot(int texture, int ws = 0, int wt = 0) {
  cl::LuxTextureSlot s{};
  s.m00 = s.m11 = 1.0f;
  s.texture = texture;
  s.flags = LUX_SLOT_MAKE_WRAP(ws, wt);
  return s;
}

TEST(TexturePack, CopiesRgba8AndHalvesWithFlagsAndOffsets) {
  Rng rng(31);
  scene::Scene s;
  s.textures.push_back(make_texture("albedo", 5, 3, scene::ColorSpace::kSRGB, rng));
  s.textures.push_back(make_texture("roughness", 4, 7, scene::ColorSpace::kLinear, rng));
  s.textures.push_back(make_texture("hdr", 2, 3, scene::ColorSpace::kSRGB, rng, true));
  auto pack = pack_textures(s);
  ASSERT_TRUE(pack.is_ok()) << pack.status().to_string();
  ASSERT_EQ(pack->textures.size(), 3u);
  EXPECT_EQ(pack->textures[0].flags, LUX_TEXTURE_FLAG_SRGB);
  EXPECT_EQ(pack->textures[1].flags, 0);
  EXPECT_EQ(pack->textures[2].flags, LUX_TEXTURE_FLAG_HALF);
  EXPECT_EQ(pack->textures[1].offset, 15);
  EXPECT_EQ(pack->textures[2].offset, 15 + 28);
  EXPECT_EQ(pack->texels.size(), 15u + 28u + 12u);  // halves: two words per texel
  EXPECT_EQ(pack->bytes(), 55u * 4 + 3 * sizeof(cl::LuxTexture));
  // Host and device hold the same bytes per texel: 4 (RGBA8), 8 (halves).
  EXPECT_EQ(s.textures[0].pixel_bytes(), 15u * 4);
  EXPECT_EQ(s.textures[2].pixel_bytes(), 6u * 8);
  // R in the low byte, alpha in the high byte, the codes unchanged.
  const uint8_t* p = &s.textures[1].rgba8[0];
  EXPECT_EQ(pack->texels[15],
            uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24);
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

TEST(HalfFloat, RoundsToNearestEvenAndRoundTrips) {
  EXPECT_EQ(float_to_half(1.0f), 0x3c00);
  EXPECT_EQ(float_to_half(65504.0f), 0x7bff);
  EXPECT_EQ(float_to_half(65520.0f), 0x7c00);             // rounds past the largest half
  EXPECT_EQ(float_to_half(1.0f + 0x1p-11f), 0x3c00);      // tie: to even
  EXPECT_EQ(float_to_half(1.0f + 3 * 0x1p-11f), 0x3c02);  // tie: to even (up)
  EXPECT_EQ(float_to_half(0x1p-24f), 0x0001);             // least subnormal
  EXPECT_EQ(float_to_half(0x1p-25f), 0x0000);             // tie below it: to even (0)
  EXPECT_EQ(float_to_half(-2.0f), 0xc000);
  for (uint32_t h = 0; h < 0x7c00; ++h)  // every finite non-negative half
    ASSERT_EQ(float_to_half(half_to_float(uint16_t(h))), h) << h;
}

TEST(TextureSample, SrgbDecodeMatchesTheEotfAtEveryCode) {
  // 256 x 1: texel x has code x in every channel (alpha x too, linear).
  scene::Texture t;
  t.name = "ramp";
  t.source_space = scene::ColorSpace::kSRGB;
  t.width = 256;
  t.height = 1;
  for (int x = 0; x < 256; ++x)
    t.rgba8.insert(t.rgba8.end(), {uint8_t(x), uint8_t(x), uint8_t(x), uint8_t(x)});
  scene::Texture data = t;
  data.source_space = scene::ColorSpace::kLinear;
  scene::Scene s;
  s.textures = {t, data};
  auto pack = pack_textures(s);
  ASSERT_TRUE(pack.is_ok());
  std::vector<cl::float2> uv;
  for (int x = 0; x < 256; ++x) uv.push_back({(x + 0.5f) / 256, 0.5f});
  auto srgb = test::probe_texture(pack.value(), 0, uv);
  auto linear = test::probe_texture(pack.value(), 1, uv);
  ASSERT_TRUE(srgb.is_ok() && linear.is_ok());
  for (int x = 0; x < 256; ++x) {
    const double expect = srgb_eotf(x / 255.0);
    ASSERT_NEAR((*srgb)[size_t(x)].x, expect, 1e-7 + 1e-6 * expect) << "code " << x;
    ASSERT_NEAR((*srgb)[size_t(x)].w, x / 255.0, 1e-7) << "alpha stays linear, code " << x;
    ASSERT_NEAR((*linear)[size_t(x)].y, x / 255.0, 1e-7) << "code " << x;
    // The host decode agrees with the device one.
    ASSERT_NEAR(s.textures[0].linear(size_t(x)).z, expect, 1e-7 + 1e-6 * expect);
  }
  // Injected error: decoding as linear would be off by far more than the bound.
  EXPECT_GT(std::fabs((*linear)[128].x - srgb_eotf(128 / 255.0)), 0.2);
}

TEST(TextureSample, BilinearUnderEachWrapModeMatchesTable820) {
  Rng rng(32);
  scene::Scene s;
  s.textures.push_back(make_texture("albedo", 5, 3, scene::ColorSpace::kSRGB, rng));
  s.textures.push_back(make_texture("data", 4, 7, scene::ColorSpace::kLinear, rng));
  s.textures.push_back(make_texture("hdr", 3, 4, scene::ColorSpace::kLinear, rng, true));
  auto pack = pack_textures(s);
  ASSERT_TRUE(pack.is_ok());
  std::vector<cl::float2> uv;
  for (int i = 0; i < 1000; ++i)
    uv.push_back({rng.uniform() * 6 - 3, rng.uniform() * 6 - 3});  // outside [0, 1] both ways
  uv.push_back({0, 0});
  uv.push_back({0.1f, 1.0f / 6});
  uv.push_back({1e3f + 0.25f, -0.75f});
  const int modes[3] = {LUX_WRAP_REPEAT, LUX_WRAP_CLAMP, LUX_WRAP_MIRROR};
  for (int tex = 0; tex < 3; ++tex)
    for (int ws : modes)
      for (int wt : modes) {
        auto out = test::probe_texture_slot(pack.value(), identity_slot(tex, ws, wt), uv, uv);
        ASSERT_TRUE(out.is_ok()) << out.status().to_string();
        for (size_t i = 0; i < uv.size(); ++i) {
          const auto ref = reference_sample(s.textures[size_t(tex)], uv[i].x, uv[i].y, ws, wt);
          const float got[4] = {(*out)[i].x, (*out)[i].y, (*out)[i].z, (*out)[i].w};
          for (size_t k = 0; k < 4; ++k)
            ASSERT_NEAR(got[k], ref[k], 4e-5 * (1 + std::fabs(ref[k])))
                << "texture " << tex << " wrap " << ws << "/" << wt << " uv (" << uv[i].x << ", "
                << uv[i].y << ") channel " << k;
        }
      }
}

TEST(TextureSample, WrapModesAtTexelCentresFollowTheirFormulas) {
  // Closed form: at a coordinate whose wrapped value is a texel centre the
  // filter returns that texel alone. 4 x 1 texture, texel x has code 60 x.
  scene::Texture t;
  t.width = 4;
  t.height = 1;
  for (int x = 0; x < 4; ++x) t.rgba8.insert(t.rgba8.end(), {uint8_t(60 * x), 0, 0, 255});
  scene::Scene s;
  s.textures = {t};
  auto pack = pack_textures(s);
  ASSERT_TRUE(pack.is_ok());
  // repeat: u - floor(u); clamp: clamp(u, 0, 1); mirrored repeat: the
  // period-2 triangle wave 1 - |(u mod 2) - 1|.
  const std::function<double(double)> formula[3] = {
      [](double u) { return u - std::floor(u); }, [](double u) { return std::clamp(u, 0.0, 1.0); },
      [](double u) { return 1 - std::fabs(u - 2 * std::floor(u / 2) - 1); }};
  std::vector<cl::float2> uv;
  for (int k = -12; k < 12; ++k) uv.push_back({(k + 0.5f) / 4, 0.5f});  // centres, u in [-3, 3)
  for (int mode = 0; mode < 3; ++mode) {
    auto out = test::probe_texture_slot(pack.value(), identity_slot(0, mode, 0), uv, uv);
    ASSERT_TRUE(out.is_ok());
    for (size_t i = 0; i < uv.size(); ++i) {
      const double w = formula[mode](uv[i].x);
      const int x = std::min(int(std::floor(w * 4)), 3);
      EXPECT_NEAR((*out)[i].x, 60 * x / 255.0, 1e-6) << "mode " << mode << " u " << uv[i].x;
    }
  }
  // Injected error: the three modes disagree at u = -0.375 (texel centre
  // -2): repeat reads texel 2, clamp texel 0, mirror texel 1.
  std::vector<float> at;
  for (int mode = 0; mode < 3; ++mode)
    at.push_back((*test::probe_texture_slot(pack.value(), identity_slot(0, mode, 0),
                                            {{-0.375f, 0.5f}}, {{-0.375f, 0.5f}}))[0]
                     .x);
  EXPECT_NEAR(at[0], 120 / 255.0, 1e-6);
  EXPECT_NEAR(at[1], 0.0, 1e-6);
  EXPECT_NEAR(at[2], 60 / 255.0, 1e-6);
}

TEST(TextureSample, KhrTextureTransformAndUvSetFollowTheExtension) {
  Rng rng(34);
  scene::Scene s;
  s.textures.push_back(make_texture("albedo", 7, 5, scene::ColorSpace::kSRGB, rng));
  auto pack = pack_textures(s);
  ASSERT_TRUE(pack.is_ok());
  scene::TextureRef ref;
  ref.texture = 0;
  ref.texcoord = 1;
  ref.has_transform = true;
  ref.offset = {0.3f, -0.7f};
  ref.rotation = 0.6f;
  ref.scale = {2.5f, -1.5f};
  ref.wrap_s = scene::WrapMode::kMirroredRepeat;
  // uv_matrix is T * R * S of the extension's 3 x 3 matrices.
  const double c = std::cos(0.6), sn = std::sin(0.6);
  const double T[3][3] = {{1, 0, 0.3}, {0, 1, -0.7}, {0, 0, 1}};
  const double R[3][3] = {{c, sn, 0}, {-sn, c, 0}, {0, 0, 1}};
  const double S[3][3] = {{2.5, 0, 0}, {0, -1.5, 0}, {0, 0, 1}};
  double TR[3][3] = {}, M[3][3] = {};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) TR[i][j] += T[i][k] * R[k][j];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) M[i][j] += TR[i][k] * S[k][j];
  const auto m = ref.uv_matrix();
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(m[size_t(i)], M[i / 3][i % 3], 1e-7) << i;

  cl::LuxTextureSlot slot{};
  slot.texture = 0;
  slot.m00 = float(m[0]), slot.m01 = float(m[1]), slot.m02 = float(m[2]);
  slot.m10 = float(m[3]), slot.m11 = float(m[4]), slot.m12 = float(m[5]);
  slot.flags = LUX_SLOT_TEXCOORD1 | LUX_SLOT_TRANSFORM | LUX_SLOT_MAKE_WRAP(LUX_WRAP_MIRROR, 0);
  std::vector<cl::float2> uv0, uv1;
  for (int i = 0; i < 500; ++i) {
    uv0.push_back({rng.uniform() * 2 - 0.5f, rng.uniform() * 2 - 0.5f});
    uv1.push_back({rng.uniform() * 2 - 0.5f, rng.uniform() * 2 - 0.5f});
  }
  auto out = test::probe_texture_slot(pack.value(), slot, uv0, uv1);
  ASSERT_TRUE(out.is_ok()) << out.status().to_string();
  size_t differs_from_set0 = 0;
  for (size_t i = 0; i < uv0.size(); ++i) {
    const double u = uv1[i].x, v = uv1[i].y;
    const double tu = M[0][0] * u + M[0][1] * v + M[0][2], tv = M[1][0] * u + M[1][1] * v + M[1][2];
    const auto want = reference_sample(s.textures[0], tu, tv, LUX_WRAP_MIRROR, LUX_WRAP_REPEAT);
    ASSERT_NEAR((*out)[i].x, want[0], 2e-4) << i;
    ASSERT_NEAR((*out)[i].w, want[3], 2e-4) << i;
    // Injected error: reading TEXCOORD_0 instead would not pass.
    const double wu = M[0][0] * uv0[i].x + M[0][1] * uv0[i].y + M[0][2],
                 wv = M[1][0] * uv0[i].x + M[1][1] * uv0[i].y + M[1][2];
    const auto wrong = reference_sample(s.textures[0], wu, wv, LUX_WRAP_MIRROR, LUX_WRAP_REPEAT);
    differs_from_set0 += std::fabs(wrong[0] - want[0]) > 1e-3;
  }
  EXPECT_GT(differs_from_set0, uv0.size() / 2);
  // Without the transform flag the UV is read unchanged (bit for bit).
  slot.flags = LUX_SLOT_TEXCOORD1;
  auto plain = test::probe_texture_slot(pack.value(), slot, uv0, uv1);
  auto direct = test::probe_texture(pack.value(), 0, uv1);
  ASSERT_TRUE(plain.is_ok() && direct.is_ok());
  for (size_t i = 0; i < uv0.size(); ++i) ASSERT_EQ((*plain)[i].x, (*direct)[i].x);
}

}  // namespace
}  // namespace luxel::pipeline
