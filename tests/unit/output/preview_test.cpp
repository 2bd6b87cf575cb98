// PNG previews: decoded independently with OpenImageIO.
#include "output/preview.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "output/tone_map.h"
#include "temp_dir.h"

namespace luxel::output {
namespace {

using testing::TempDir;

struct Decoded {
  int width = 0, height = 0, channels = 0;
  std::string format;
  std::vector<uint8_t> pixels;
  uint8_t at(int x, int y, int c) const {
    return pixels[(static_cast<size_t>(y) * width + x) * channels + c];
  }
};

// Decodes with alpha left unassociated, as written (OpenImageIO would
// otherwise premultiply on read).
Decoded decode(const std::string& name, OIIO::Filesystem::IOProxy* proxy = nullptr) {
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  if (proxy) config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
  auto in = OIIO::ImageInput::open(name, &config);
  Decoded d;
  if (!in) {
    ADD_FAILURE() << "cannot decode " << name << ": " << OIIO::geterror();
    return d;
  }
  const OIIO::ImageSpec& spec = in->spec();
  d.width = spec.width, d.height = spec.height, d.channels = spec.nchannels;
  d.format = in->format_name();
  EXPECT_EQ(spec.format, OIIO::TypeDesc::UINT8);
  d.pixels.resize(static_cast<size_t>(d.width) * d.height * d.channels);
  EXPECT_TRUE(in->read_image(0, 0, 0, d.channels, OIIO::TypeDesc::UINT8, d.pixels.data()));
  return d;
}

Decoded decode_memory(std::vector<uint8_t>& bytes) {
  OIIO::Filesystem::IOMemReader reader(bytes.data(), bytes.size());
  return decode("preview.png", &reader);
}

// Every texel grey `value`, covered.
Image grey(int width, int height, float value) {
  Image image = make_image(width, height, 4, value);
  for (size_t i = 0; i < image.texel_count(); ++i) image.pixels[i * 4 + 3] = 1.0f;
  return image;
}

TEST(Preview, WritesAnRgbaPngWithCoverageAlpha) {
  TempDir dir("preview");
  Image image = grey(40, 24, 0.5f);
  for (int y = 0; y < 24; ++y) image.at(3, y, 3) = 0.0f;  // an uncovered column
  const std::string path = dir.file("preview.png");
  ASSERT_TRUE(write_png_preview(path, image).is_ok());
  EXPECT_TRUE(dir.temporaries().empty());
  const Decoded png = decode(path);
  EXPECT_EQ(png.format, "png");
  ASSERT_EQ(png.width, 40);
  ASSERT_EQ(png.height, 24);
  ASSERT_EQ(png.channels, 4);
  EXPECT_EQ(png.at(3, 10, 3), 0);
  EXPECT_EQ(png.at(4, 10, 3), 255);
  // Auto exposure maps this uniform grey to 0.8 display, sRGB 0.906 -> 231;
  // the uncovered column keeps its colour under alpha 0.
  EXPECT_NEAR(png.at(10, 10, 0), 231, 1);
  EXPECT_EQ(png.at(3, 10, 0), png.at(10, 10, 0));
}

TEST(Preview, ToneCurveIsMonotonic) {
  double previous = -1.0;
  for (double x = 0.0; x < 1e7; x = x * 1.01 + 1e-6) {
    const double y = srgb_oetf(reinhard_luminance(x, x, x, 1.0)[0]);
    ASSERT_GE(y, previous) << "at " << x;
    ASSERT_LE(y, 1.0);
    previous = y;
  }
  TempDir dir("preview-ramp");
  Image ramp = make_image(256, 1, 3);
  for (int x = 0; x < 256; ++x)
    for (int c = 0; c < 3; ++c) ramp.at(x, 0, c) = std::pow(10.0f, -4.0f + 8.0f * x / 255.0f);
  const std::string path = dir.file("ramp.png");
  ASSERT_TRUE(write_png_preview(path, ramp, {.exposure = 0, .auto_exposure = false}).is_ok());
  const Decoded png = decode(path);
  ASSERT_EQ(png.width, 256);
  for (int x = 1; x < 256; ++x) ASSERT_GE(png.at(x, 0, 1), png.at(x - 1, 0, 1)) << "at " << x;
  EXPECT_LE(png.at(0, 0, 1), 1);
  EXPECT_EQ(png.at(255, 0, 1), 255);
  EXPECT_EQ(png.at(200, 0, 3), 255) << "an RGB input counts as covered";
}

TEST(Preview, AutoExposureUsesThe95thPercentileOfCoveredTexels) {
  Image image = make_image(10, 11, 4);
  for (int i = 0; i < 100; ++i) {
    for (int c = 0; c < 3; ++c) image.pixels[i * 4 + c] = static_cast<float>(i + 1);
    image.pixels[i * 4 + 3] = 1.0f;
  }
  // The last row is uncovered and very bright: it must not count.
  for (int i = 100; i < 110; ++i)
    for (int c = 0; c < 3; ++c) image.pixels[i * 4 + c] = 1e9f;
  // floor(0.95 * 99) = index 94 of the sorted luminances 1..100 -> 95.
  EXPECT_NEAR(preview_exposure_scale(image), 4.0 / 95.0, 1e-12);
  EXPECT_NEAR(preview_exposure_scale(image, {.exposure = 1.0f}), 8.0 / 95.0, 1e-12);
  EXPECT_EQ(preview_exposure_scale(image, {.exposure = 2.0f, .auto_exposure = false}), 4.0);
}

TEST(Preview, AutoExposureSurvivesZerosHugeValuesAndNonFinite) {
  TempDir dir("preview-extreme");
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  struct Case {
    const char* name;
    Image image;
    int expected_red;  // decoded 8-bit red of texel (0, 0)
  };
  Image mixed = grey(8, 8, 1e6f);
  mixed.at(0, 0, 0) = nan, mixed.at(1, 0, 1) = inf, mixed.at(2, 0, 2) = -inf;
  std::vector<Case> cases = {{"zeros", grey(8, 8, 0.0f), 0},
                             {"huge", grey(8, 8, 1e6f), 231},
                             {"nothing_covered", make_image(8, 8, 4, 0.0f), 0},
                             {"non_finite", mixed, -1}};
  for (Case& c : cases) {
    const double k = preview_exposure_scale(c.image);
    EXPECT_TRUE(std::isfinite(k) && k > 0.0) << c.name << ": k = " << k;
    const std::string path = dir.file(std::string(c.name) + ".png");
    ASSERT_TRUE(write_png_preview(path, c.image).is_ok()) << c.name;
    const Decoded png = decode(path);
    ASSERT_EQ(png.width, 8) << c.name;
    if (c.expected_red >= 0) EXPECT_NEAR(png.at(0, 0, 0), c.expected_red, 1) << c.name;
    if (std::string(c.name) == "huge")
      for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
          for (int ch = 0; ch < 3; ++ch) ASSERT_NEAR(png.at(x, y, ch), 231, 1);
          ASSERT_EQ(png.at(x, y, 3), 255);
        }
  }
}

TEST(Preview, EncodedPreviewIsDownscaledKeepingAspect) {
  Image image = grey(300, 100, 2.0f);
  auto bytes = encode_png_preview(image, 64);
  ASSERT_TRUE(bytes.is_ok()) << bytes.status().to_string();
  const Decoded png = decode_memory(*bytes);
  EXPECT_EQ(png.width, 64);
  EXPECT_EQ(png.height, 21);  // 100 * 64 / 300 = 21.3
  EXPECT_NEAR(png.at(30, 10, 0), 231, 1);

  auto tall = encode_png_preview(grey(3, 500, 1.0f), 50);
  ASSERT_TRUE(tall.is_ok());
  const Decoded tall_png = decode_memory(*tall);
  EXPECT_EQ(tall_png.width, 1);
  EXPECT_EQ(tall_png.height, 50);

  auto small = encode_png_preview(grey(10, 5, 1.0f), 64);
  ASSERT_TRUE(small.is_ok());
  const Decoded small_png = decode_memory(*small);
  EXPECT_EQ(small_png.width, 10) << "never enlarged";
  EXPECT_EQ(small_png.height, 5);

  EXPECT_EQ(encode_png_preview(image, 0).status().code(), StatusCode::kInvalidArgument);
}

TEST(Preview, BoxFilterWeightsByCoverage) {
  // Left half covered with value 2, right half uncovered black: the average
  // colour is 2 (not 1), the average coverage 0.5.
  Image image = make_image(4, 4, 4, 0.0f);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 2; ++x)
      image.at(x, y, 0) = image.at(x, y, 1) = image.at(x, y, 2) = 2.0f, image.at(x, y, 3) = 1.0f;
  auto small = downscale_box(image, 1);
  ASSERT_TRUE(small.is_ok());
  ASSERT_EQ(small->width, 1);
  EXPECT_FLOAT_EQ(small->at(0, 0, 0), 2.0f);
  EXPECT_FLOAT_EQ(small->at(0, 0, 3), 0.5f);
  auto half = downscale_box(image, 2);
  ASSERT_TRUE(half.is_ok());
  EXPECT_FLOAT_EQ(half->at(0, 1, 0), 2.0f);
  EXPECT_FLOAT_EQ(half->at(1, 1, 3), 0.0f);
}

TEST(Preview, ErrorsNameThePath) {
  TempDir dir("preview-errors");
  const std::string path = dir.file("p.png");
  Status st = write_png_preview(path, make_image(4, 4, 2));
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(st.message().find(path), std::string::npos) << st.message();
  st = write_png_preview(path, Image{});
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(st.message().find(path), std::string::npos) << st.message();
  const std::string unwritable = dir.file("nope/p.png");
  st = write_png_preview(unwritable, grey(2, 2, 1.0f));
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(st.message().find(unwritable), std::string::npos) << st.message();
  EXPECT_TRUE(dir.temporaries().empty());
}

}  // namespace
}  // namespace luxel::output
