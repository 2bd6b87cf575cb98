// read_reference_exr: the reference lightmap of benchmark mode, one rule for
// the local bake and the daemon (RGB or RGBA, RGBA out).
#include "output/reference_exr.h"

#include <gtest/gtest.h>

#include "output/exr.h"
#include "temp_dir.h"

namespace luxel::output {
namespace {

using testing::TempDir;

Image ramp(int width, int height, int channels) {
  Image image = make_image(width, height, channels);
  for (size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] = 0.25f * float(i) + 0.5f;
  return image;
}

void expect_error_naming(const Result<Image>& r, const std::string& path,
                         const std::string& detail) {
  ASSERT_FALSE(r.is_ok());
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument) << r.status().to_string();
  EXPECT_NE(r.status().message().find(path), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find(detail), std::string::npos) << r.status().message();
}

TEST(ReferenceExr, RgbaIsReturnedAsIs) {
  TempDir dir("reference-rgba");
  const Image image = ramp(5, 3, 4);
  ASSERT_TRUE(write_exr(dir.file("ref.exr"), image, kRgbaChannels).is_ok());
  auto r = read_reference_exr(dir.file("ref.exr"));
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  EXPECT_EQ(r->width, 5);
  EXPECT_EQ(r->height, 3);
  EXPECT_EQ(r->channels, 4);
  EXPECT_EQ(r->pixels, image.pixels);
}

TEST(ReferenceExr, RgbGetsAlphaOne) {
  TempDir dir("reference-rgb");
  const Image image = ramp(4, 2, 3);
  ASSERT_TRUE(write_exr(dir.file("ref.exr"), image, {"R", "G", "B"}).is_ok());
  auto r = read_reference_exr(dir.file("ref.exr"), 4, 2);
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  ASSERT_EQ(r->channels, 4);
  ASSERT_EQ(r->pixels.size(), 4u * 2u * 4u);
  for (size_t t = 0; t < 8; ++t) {
    for (size_t c = 0; c < 3; ++c) EXPECT_EQ(r->pixels[t * 4 + c], image.pixels[t * 3 + c]);
    EXPECT_EQ(r->pixels[t * 4 + 3], 1.0f) << "texel " << t;
  }
}

TEST(ReferenceExr, OtherChannelCountsAreRefusedNamingTheFile) {
  TempDir dir("reference-channels");
  ASSERT_TRUE(write_exr(dir.file("y.exr"), ramp(2, 2, 1), kLuminanceChannel).is_ok());
  expect_error_naming(read_reference_exr(dir.file("y.exr")), dir.file("y.exr"), "1 channels");
  ASSERT_TRUE(write_exr(dir.file("ya.exr"), ramp(2, 2, 2), {"Y", "A"}).is_ok());
  expect_error_naming(read_reference_exr(dir.file("ya.exr")), dir.file("ya.exr"), "2 channels");
  ASSERT_TRUE(write_exr(dir.file("c5.exr"), ramp(2, 2, 5), {"A", "B", "G", "R", "Z"}).is_ok());
  expect_error_naming(read_reference_exr(dir.file("c5.exr")), dir.file("c5.exr"), "5 channels");
}

TEST(ReferenceExr, SizeMismatchIsRefusedNamingBothSizes) {
  TempDir dir("reference-size");
  ASSERT_TRUE(write_exr(dir.file("ref.exr"), ramp(4, 2, 4), kRgbaChannels).is_ok());
  expect_error_naming(read_reference_exr(dir.file("ref.exr"), 8, 2), dir.file("ref.exr"),
                      "4x2 texels, the lightmap is 8x2");
  EXPECT_TRUE(read_reference_exr(dir.file("ref.exr"), 4, 2).is_ok());
}

TEST(ReferenceExr, MissingFileKeepsTheReadersCode) {
  TempDir dir("reference-missing");
  auto r = read_reference_exr(dir.file("none.exr"));
  ASSERT_FALSE(r.is_ok());
  EXPECT_EQ(r.status().code(), StatusCode::kNotFound) << r.status().to_string();
  EXPECT_NE(r.status().message().find(dir.file("none.exr")), std::string::npos);
}

}  // namespace
}  // namespace luxel::output
