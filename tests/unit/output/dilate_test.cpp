// Dilation: rings, untouched covered texels, preserved alpha, no bleed.
#include "output/dilate.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <random>

namespace luxel::output {
namespace {

constexpr float kSentinel = -7.0f;  // marks texels dilation must not write

// An RGBA image with nothing covered and RGB set to the sentinel.
Image uncovered(int width, int height) {
  Image image = make_image(width, height, 4, kSentinel);
  for (size_t i = 0; i < image.texel_count(); ++i) image.pixels[i * 4 + 3] = 0.0f;
  return image;
}

// The rule written out naively: full scans, a copy per pass.
Image reference_dilate(Image image, int radius) {
  std::vector<bool> filled(image.texel_count());
  for (size_t i = 0; i < filled.size(); ++i) filled[i] = image.pixels[i * 4 + 3] > 0.0f;
  for (int pass = 0; pass < radius; ++pass) {
    const Image before = image;
    const std::vector<bool> was = filled;
    for (int y = 0; y < image.height; ++y)
      for (int x = 0; x < image.width; ++x) {
        if (was[static_cast<size_t>(y) * image.width + x]) continue;
        double sum[3] = {0, 0, 0};
        int n = 0;
        for (int ny = std::max(0, y - 1); ny <= std::min(image.height - 1, y + 1); ++ny)
          for (int nx = std::max(0, x - 1); nx <= std::min(image.width - 1, x + 1); ++nx) {
            if (!was[static_cast<size_t>(ny) * image.width + nx]) continue;
            ++n;
            for (int c = 0; c < 3; ++c) sum[c] += before.at(nx, ny, c);
          }
        if (n == 0) continue;
        for (int c = 0; c < 3; ++c) image.at(x, y, c) = static_cast<float>(sum[c] / n);
        filled[static_cast<size_t>(y) * image.width + x] = true;
      }
  }
  return image;
}

std::vector<float> alpha_of(const Image& image) {
  std::vector<float> a(image.texel_count());
  for (size_t i = 0; i < a.size(); ++i) a[i] = image.pixels[i * 4 + 3];
  return a;
}

TEST(Dilate, SingleTexelSpreadsExactlyRadiusRings) {
  for (int radius : {0, 1, 3, 6}) {
    Image image = uncovered(15, 13);
    const int cx = 7, cy = 5;
    image.at(cx, cy, 0) = 1.0f, image.at(cx, cy, 1) = 2.0f, image.at(cx, cy, 2) = 3.0f;
    image.at(cx, cy, 3) = 0.25f;
    const std::vector<float> alpha = alpha_of(image);
    ASSERT_TRUE(dilate(image, radius).is_ok());
    EXPECT_EQ(alpha_of(image), alpha) << "alpha must keep meaning coverage";
    for (int y = 0; y < image.height; ++y)
      for (int x = 0; x < image.width; ++x) {
        const int ring = std::max(std::abs(x - cx), std::abs(y - cy));
        for (int c = 0; c < 3; ++c) {
          const float expected = ring <= radius ? static_cast<float>(c + 1) : kSentinel;
          ASSERT_EQ(image.at(x, y, c), expected)
              << "radius " << radius << " texel (" << x << ", " << y << ") channel " << c;
        }
      }
  }
}

TEST(Dilate, AveragesFilledNeighboursOfThePreviousRing) {
  // Row of 5: covered values 2 at x=0 and 6 at x=4. Pass 1 fills x=1 (2) and
  // x=3 (6); pass 2 fills x=2 with the mean of both: 4.
  Image image = uncovered(5, 1);
  for (int c = 0; c < 3; ++c) image.at(0, 0, c) = 2.0f, image.at(4, 0, c) = 6.0f;
  image.at(0, 0, 3) = image.at(4, 0, 3) = 1.0f;
  ASSERT_TRUE(dilate(image, 2).is_ok());
  EXPECT_EQ(image.at(1, 0, 0), 2.0f);
  EXPECT_EQ(image.at(2, 0, 0), 4.0f);
  EXPECT_EQ(image.at(3, 0, 0), 6.0f);
}

TEST(Dilate, MatchesTheNaiveRuleOnRandomCharts) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> value(0.0f, 10.0f);
  for (int trial = 0; trial < 5; ++trial) {
    Image image = uncovered(41, 29);
    // Sparse random rectangles of coverage stand in for charts.
    for (int r = 0; r < 6; ++r) {
      const int x0 = static_cast<int>(rng() % 38), y0 = static_cast<int>(rng() % 26);
      const int w = 1 + static_cast<int>(rng() % 5), h = 1 + static_cast<int>(rng() % 4);
      for (int y = y0; y < std::min(image.height, y0 + h); ++y)
        for (int x = x0; x < std::min(image.width, x0 + w); ++x) {
          for (int c = 0; c < 3; ++c) image.at(x, y, c) = value(rng);
          image.at(x, y, 3) = 0.1f + 0.9f * value(rng) / 10.0f;
        }
    }
    const int radius = 1 + trial;
    const Image expected = reference_dilate(image, radius);
    Image got = image;
    ASSERT_TRUE(dilate(got, radius).is_ok());
    for (size_t i = 0; i < image.texel_count(); ++i) {
      const bool covered = image.pixels[i * 4 + 3] > 0.0f;
      for (int c = 0; c < 4; ++c) {
        const size_t k = i * 4 + c;
        if (covered || c == 3)
          ASSERT_EQ(got.pixels[k], image.pixels[k]) << "covered texels and alpha never change";
        else
          ASSERT_NEAR(got.pixels[k], expected.pixels[k], 1e-5f) << "texel " << i;
      }
    }
    Image again = image;
    ASSERT_TRUE(dilate(again, radius).is_ok());
    EXPECT_EQ(again.pixels, got.pixels) << "deterministic";
  }
}

TEST(Dilate, AllUncoveredImageStaysEmpty) {
  Image image = uncovered(16, 16);
  const Image before = image;
  ASSERT_TRUE(dilate(image, 8).is_ok());
  EXPECT_EQ(image.pixels, before.pixels);
}

TEST(Dilate, SeparateCoverageImageDilatesEveryChannel) {
  Image image = make_image(6, 1, 2, kSentinel);
  Image coverage = make_image(6, 1, 1, 0.0f);
  image.at(0, 0, 0) = 5.0f, image.at(0, 0, 1) = -1.0f;
  coverage.at(0, 0, 0) = 1.0f;
  ASSERT_TRUE(dilate(image, coverage, 2).is_ok());
  EXPECT_EQ(image.at(2, 0, 0), 5.0f);
  EXPECT_EQ(image.at(2, 0, 1), -1.0f);
  EXPECT_EQ(image.at(3, 0, 0), kSentinel);
  EXPECT_EQ(dilate(image, make_image(5, 1, 1), 2).code(), StatusCode::kInvalidArgument);
}

TEST(Dilate, RejectsBadArguments) {
  Image rgb = make_image(4, 4, 3);
  EXPECT_EQ(dilate(rgb, 1).code(), StatusCode::kInvalidArgument);
  Image rgba = make_image(4, 4, 4);
  EXPECT_EQ(dilate(rgba, -1).code(), StatusCode::kInvalidArgument);
  Image empty;
  EXPECT_EQ(dilate(empty, 1).code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace luxel::output
