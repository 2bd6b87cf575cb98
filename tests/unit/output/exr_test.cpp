// OpenEXR writer and reader: bit-exact float round trips, metadata, errors.
#include "output/exr.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "output/preview.h"
#include "temp_dir.h"

namespace luxel::output {
namespace {

using testing::read_bytes;
using testing::TempDir;
using testing::write_bytes;

// Floats of every kind EXR must keep: tiny, huge, negative, denormal, signed
// zero, infinities and NaN.
Image awkward_rgba(int width, int height, uint32_t seed) {
  Image image = make_image(width, height, 4);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> exponent(-40.0f, 38.0f);
  for (float& v : image.pixels) v = std::pow(10.0f, exponent(rng)) * (rng() % 2 ? 1.0f : -1.0f);
  image.pixels[0] = std::numeric_limits<float>::denorm_min();
  image.pixels[1] = -0.0f;
  image.pixels[2] = std::numeric_limits<float>::infinity();
  image.pixels[3] = -std::numeric_limits<float>::infinity();
  image.pixels[4] = std::numeric_limits<float>::quiet_NaN();
  image.pixels[5] = std::numeric_limits<float>::max();
  return image;
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

TEST(Exr, RgbaRoundTripIsBitExactWithMetadata) {
  TempDir dir("exr-rgba");
  const Image image = awkward_rgba(37, 23, 7);
  const std::map<std::string, std::string> metadata = {
      {"luxel/encoding", "irradiance"}, {"luxel/units", "W/m^2"}, {"luxel/empty", ""}};
  const std::string path = dir.file("lightmap.exr");
  ASSERT_TRUE(write_exr(path, image, kRgbaChannels, metadata).is_ok());
  EXPECT_TRUE(dir.temporaries().empty());

  ExrInfo info;
  auto read = read_exr(path, &info);
  ASSERT_TRUE(read.is_ok()) << read.status().to_string();
  EXPECT_EQ(read->width, 37);
  EXPECT_EQ(read->height, 23);
  EXPECT_EQ(read->channels, 4);
  EXPECT_TRUE(same_bits(read->pixels, image.pixels));
  EXPECT_EQ(info.channel_names, kRgbaChannels);
  EXPECT_EQ(info.metadata.at("luxel/encoding"), "irradiance");
  EXPECT_EQ(info.metadata.at("luxel/units"), "W/m^2");
  EXPECT_EQ(info.metadata.at("compression"), "zip");
  // No time stamp unless asked for: the same data gives the same bytes.
  EXPECT_EQ(info.metadata.count("DateTime"), 0u);
  const std::string first = read_bytes(path);
  ASSERT_TRUE(write_exr(path, image, kRgbaChannels, metadata).is_ok());
  EXPECT_EQ(read_bytes(path), first);
}

TEST(Exr, NamedChannelsRoundTripByName) {
  TempDir dir("exr-named");
  // OpenEXR stores channels sorted by name; the reader reports the order.
  const std::vector<std::string> names = {"sh.r", "sh.g", "sh.b", "count"};
  Image image = make_image(5, 3, 4);
  for (size_t i = 0; i < image.pixels.size(); ++i)
    image.pixels[i] = 0.25f * static_cast<float>(i) - 3.0f;
  const std::string path = dir.file("sh.exr");
  ASSERT_TRUE(write_exr(path, image, names).is_ok());
  ExrInfo info;
  auto read = read_exr(path, &info);
  ASSERT_TRUE(read.is_ok()) << read.status().to_string();
  ASSERT_EQ(info.channel_names.size(), names.size());
  for (int c = 0; c < 4; ++c) {
    const auto it = std::find(info.channel_names.begin(), info.channel_names.end(), names[c]);
    ASSERT_NE(it, info.channel_names.end()) << names[c];
    const int rc = static_cast<int>(it - info.channel_names.begin());
    for (int y = 0; y < 3; ++y)
      for (int x = 0; x < 5; ++x) EXPECT_EQ(read->at(x, y, rc), image.at(x, y, c)) << names[c];
  }
}

TEST(Exr, SamplesMapIsOneChannelY) {
  TempDir dir("exr-samples");
  Image samples = make_image(9, 4, 1);
  for (size_t i = 0; i < samples.pixels.size(); ++i)
    samples.pixels[i] = static_cast<float>(i * 1000 + 16777216 - 36000);
  const std::string path = dir.file("samples.exr");
  ASSERT_TRUE(write_samples_exr(path, samples, {{"luxel/bake", "42"}}).is_ok());
  ExrInfo info;
  auto read = read_exr(path, &info);
  ASSERT_TRUE(read.is_ok()) << read.status().to_string();
  EXPECT_EQ(info.channel_names, kLuminanceChannel);
  EXPECT_EQ(info.metadata.at("luxel/encoding"), "samples_per_texel");
  EXPECT_EQ(info.metadata.at("luxel/bake"), "42");
  EXPECT_TRUE(same_bits(read->pixels, samples.pixels));
  EXPECT_EQ(write_samples_exr(dir.file("bad.exr"), make_image(2, 2, 4)).code(),
            StatusCode::kInvalidArgument);
}

TEST(Exr, WriteErrorsNameThePath) {
  TempDir dir("exr-errors");
  const std::string path = dir.file("out.exr");
  Status st = write_exr(path, Image{}, kRgbaChannels);
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(st.message().find(path), std::string::npos) << st.message();
  EXPECT_NE(st.message().find("zero size"), std::string::npos) << st.message();

  st = write_exr(path, make_image(4, 4, 3), kRgbaChannels);
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(st.message().find(path), std::string::npos) << st.message();

  Image short_pixels = make_image(4, 4, 4);
  short_pixels.pixels.pop_back();
  EXPECT_EQ(write_exr(path, short_pixels, kRgbaChannels).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(write_exr(path, make_image(2, 2, 2), {"X", "X"}).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(write_exr(path, make_image(2, 2, 4), kRgbaChannels, {{"compression", "none"}}).code(),
            StatusCode::kInvalidArgument);

  const std::string unwritable = dir.file("missing-dir/out.exr");
  st = write_exr(unwritable, make_image(4, 4, 4), kRgbaChannels);
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(st.message().find(unwritable), std::string::npos) << st.message();
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_TRUE(dir.temporaries().empty());
}

TEST(Exr, ReadErrors) {
  TempDir dir("exr-read");
  auto missing = read_exr(dir.file("missing.exr"));
  EXPECT_EQ(missing.status().code(), StatusCode::kNotFound);
  EXPECT_NE(missing.status().message().find("missing.exr"), std::string::npos);

  const std::string png = dir.file("preview.png");
  ASSERT_TRUE(write_png_preview(png, make_image(4, 4, 4, 1.0f)).is_ok());
  EXPECT_EQ(read_exr(png).status().code(), StatusCode::kInvalidArgument);

  const std::string path = dir.file("torn.exr");
  ASSERT_TRUE(write_exr(path, awkward_rgba(64, 64, 3), kRgbaChannels).is_ok());
  const std::string bytes = read_bytes(path);
  write_bytes(path, bytes.substr(0, bytes.size() / 2));
  auto torn = read_exr(path);
  EXPECT_EQ(torn.status().code(), StatusCode::kDataLoss) << torn.status().to_string();
  write_bytes(path, "not an image at all");
  EXPECT_FALSE(read_exr(path).is_ok());
}

}  // namespace
}  // namespace luxel::output
