// The equirect sky (HDR/EXR read with OpenImageIO): mapping, radiance,
// importance sampling against lux_sky_pdf (chi-square), the irradiance it
// gives, and errors for bad images.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "shading/color.h"
#include "shading_probe.h"
#include "support/chi2.h"
#include "test_scenes.h"

namespace luxel::pipeline {
namespace {

using test::Rng;

constexpr double kPi = 3.14159265358979323846;
constexpr int kW = 64, kH = 32;

// A dim gradient with a bright spot (peak 200) off the equator.
std::vector<float> spot_sky(int w = kW, int h = kH) {
  std::vector<float> rgb(size_t(w) * size_t(h) * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double dx = (x + 0.5 - 0.3 * w) * kW / w, dy = (y + 0.5 - 0.35 * h) * kH / h;
      const double spot = 200 * std::exp(-(dx * dx + dy * dy) / (2 * 2.0 * 2.0));
      float* t = &rgb[(size_t(y) * size_t(w) + size_t(x)) * 3];
      t[0] = static_cast<float>(0.2 + 0.3 * y / h + spot);
      t[1] = static_cast<float>(0.3 + 0.1 * x / w + 0.8 * spot);
      t[2] = static_cast<float>(0.5 + 0.5 * spot);
    }
  return rgb;
}

// World direction at image coordinates (s, t) for a sky rotated by `rot`
// radians about +Y, written from the mapping documented in shared/light.h.
Vec3 sky_direction(double s, double t, double rot) {
  const double theta = kPi * t, phi = 2 * kPi * (s - 0.5);
  const double lx = std::sin(theta) * std::sin(phi), ly = std::cos(theta),
               lz = -std::sin(theta) * std::cos(phi);
  return {static_cast<float>(std::cos(rot) * lx + std::sin(rot) * lz), static_cast<float>(ly),
          static_cast<float>(-std::sin(rot) * lx + std::cos(rot) * lz)};
}

struct SkyFixture : ::testing::Test {
  test::TempDir dir;
  std::string exr = dir.file("sky.exr");
  std::vector<float> rgb = spot_sky();
  void SetUp() override {
    ASSERT_TRUE(test::write_rgb_image(exr, kW, kH, rgb)) << "writing " << exr;
  }

  Result<LightTable> table(const std::string& path, float rotation_degrees) {
    LightSettings s;
    s.sky.kind = SkySettings::Kind::kEquirect;
    s.sky.equirect_path = path;
    s.sky.rotation_degrees = rotation_degrees;
    s.sky.color = {1, 0.5f, 2};
    s.sky.intensity = 1.5f;
    return build_light_table(scene::Scene{}, accel::TriangleSoup{}, s, Bounds3{});
  }
};

TEST_F(SkyFixture, TexelCentresGiveTheTexelAndThePdfCoversTheUpperHemisphere) {
  const double rot = 90 * kPi / 180;
  auto t = table(exr, 90);
  ASSERT_TRUE(t.is_ok()) << t.status().to_string();
  EXPECT_TRUE(t->has_sky && t->sky_is_image);
  ASSERT_EQ(t->sky.width, kW);
  ASSERT_EQ(t->sky.height, kH);
  ASSERT_EQ(t->sky_texels.size(), rgb.size());
  // A 64 x 32 image: blocks of one texel; one block table per normal cell.
  ASSERT_EQ(t->sky.blocks_x, kW);
  ASSERT_EQ(t->sky.blocks_y, kH);
  ASSERT_EQ(t->sky.block_width, 1);
  const size_t bins = size_t(t->sky.normal_bins) * size_t(t->sky.normal_bins);
  EXPECT_EQ(t->sky_block_cdfs.size(), bins * (kH + 1 + kH * (kW + 1)));
  EXPECT_EQ(t->sky_texel_cdfs.size(), size_t{kW} * kH * 4);
  const Vec3 scale{1.5f, 0.75f, 3.0f};

  std::vector<cl::float4> dirs;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      dirs.push_back(test::f4(sky_direction((x + 0.5) / kW, (y + 0.5) / kH, rot)));
  auto probe = test::LightProbe::create(t.value());
  ASSERT_TRUE(probe.is_ok()) << probe.status().to_string();
  // Receivers facing up, sideways, down and askew: every direction a
  // receiver sees must have a positive density (else the estimator is
  // biased), and directions far below its horizon should get none.
  const Vec3 normals[] = {{0, 1, 0}, {1, 0, 0}, {0, -1, 0}, normalize(Vec3{0.3f, -0.5f, 0.8f})};
  for (const Vec3& n : normals) {
    SCOPED_TRACE(testing::Message() << "normal " << n.x << ", " << n.y << ", " << n.z);
    auto r = (*probe)->sky(dirs, n);
    ASSERT_TRUE(r.is_ok()) << r.status().to_string();
    size_t far_below = 0, far_below_with_density = 0;
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x) {
        const size_t i = size_t(y) * kW + size_t(x);
        const Vec3 expect{rgb[i * 3] * scale.x, rgb[i * 3 + 1] * scale.y, rgb[i * 3 + 2] * scale.z};
        ASSERT_NEAR((*r)[i].x, expect.x, 1e-5 * expect.x) << "texel " << x << ", " << y;
        ASSERT_NEAR((*r)[i].y, expect.y, 1e-5 * expect.y);
        ASSERT_NEAR((*r)[i].z, expect.z, 1e-5 * expect.z);
        const float cos_n = dot(test::xyz(dirs[i]), n);
        if (cos_n > 0) ASSERT_GT((*r)[i].w, 0.0f) << "texel " << x << ", " << y << " seen by n";
        // Normal cells are about 10 degrees wide and blocks 6: beyond 53
        // degrees below the horizon no normal of the cell sees a block.
        if (cos_n < -0.6f) {
          ++far_below;
          if ((*r)[i].w > 0) ++far_below_with_density;
        }
      }
    EXPECT_GT(far_below, 0u);
    EXPECT_EQ(far_below_with_density, 0u) << "density far below the horizon";
  }
}

TEST_F(SkyFixture, ImportanceSamplingFollowsTheSkyPdf) {
  auto t = table(exr, 90);  // 16 texels of turn: the cells below stay aligned with texels
  ASSERT_TRUE(t.is_ok()) << t.status().to_string();
  auto probe = test::LightProbe::create(t.value());
  ASSERT_TRUE(probe.is_ok()) << probe.status().to_string();
  const size_t n = 500000;
  Rng rng(21);
  std::vector<cl::float4> r(n);
  for (auto& v : r) v = rng.uniform4();
  // Receivers facing up and askew (the block tables differ per normal cell).
  for (const Vec3 normal : {Vec3{0, 1, 0}, normalize(Vec3{0.6f, -0.3f, 0.7f})}) {
    SCOPED_TRACE(testing::Message()
                 << "normal " << normal.x << ", " << normal.y << ", " << normal.z);
    auto s = (*probe)->sample_at({0, 0, 0}, r, normal);
    ASSERT_TRUE(s.is_ok()) << s.status().to_string();

    // Cells: 2 x 2 texels in world (s, t) (the mapping without rotation).
    const int rows = kH / 2, cols = kW / 2;
    std::vector<double> observed(size_t(rows * cols)), expected(size_t(rows * cols));
    std::vector<cl::float4> sampled_dirs;
    for (size_t i = 0; i < n; ++i) {
      ASSERT_TRUE(s->ok(i));
      ASSERT_TRUE(s->mis(i));
      ASSERT_FALSE(s->is_delta(i));
      const Vec3 d = test::xyz(s->wi_pdf[i]);
      ASSERT_NEAR(length(d), 1.0f, 1e-5f);
      double u = 0.5 + std::atan2(d.x, -d.z) / (2 * kPi),
             v = std::acos(std::clamp(d.y, -1.0f, 1.0f)) / kPi;
      const int c = std::min(int(u * cols), cols - 1), row = std::min(int(v * rows), rows - 1);
      observed[size_t(row * cols + c)] += 1;
      sampled_dirs.push_back(s->wi_pdf[i]);
    }
    // lux_sky_pdf integrated per cell: pdf x sin(theta) is constant inside a
    // texel, so a 4 x 4 midpoint rule (2 x 2 per texel) is exact.
    const int sub = 4;
    std::vector<cl::float4> dirs;
    std::vector<double> weight;
    for (int row = 0; row < rows; ++row)
      for (int c = 0; c < cols; ++c)
        for (int i = 0; i < sub; ++i)
          for (int j = 0; j < sub; ++j) {
            const double u = (c + (j + 0.5) / sub) / cols, v = (row + (i + 0.5) / sub) / rows;
            dirs.push_back(test::f4(sky_direction(u, v, 0)));
            weight.push_back(std::sin(kPi * v) * (kPi / rows / sub) * (2 * kPi / cols / sub));
          }
    auto pdf = (*probe)->sky(dirs, normal);
    ASSERT_TRUE(pdf.is_ok());
    double total = 0;
    for (size_t k = 0; k < dirs.size(); ++k) {
      const size_t cell = k / (sub * sub);
      expected[cell] += (*pdf)[k].w * weight[k] * n;
      total += (*pdf)[k].w * weight[k];
    }
    EXPECT_NEAR(total, 1.0, 1e-3) << "lux_sky_pdf integrates to 1 over the sphere";
    const double alpha = test_support::sidak_alpha(0.01, 5);
    const auto chi2 = test_support::chi2_test(observed, expected, alpha);
    EXPECT_GT(chi2.p_value, alpha) << chi2.detail;

    // MIS consistency: lux_sky_pdf along a sampled direction is the sampled
    // pdf (but for directions that round into a neighbouring texel).
    auto again = (*probe)->sky(sampled_dirs, normal);
    ASSERT_TRUE(again.is_ok());
    size_t mismatches = 0;
    for (size_t i = 0; i < n; ++i) {
      if (std::fabs((*again)[i].w / s->wi_pdf[i].w - 1) > 1e-3) ++mismatches;
      const Vec3 rad = test::xyz(s->radiance_dist[i]), looked_up = test::xyz((*again)[i]);
      if (std::fabs(rad.x - looked_up.x) > 1e-4f * rad.x) ++mismatches;
    }
    EXPECT_LT(mismatches, n / 1000);
  }
}

// Irradiance on +Y and -Y normals from light samples drawn for each normal
// against the exact texel integral (rotation about Y changes neither): per
// texel L * integral of |cos| = L dphi |sin^2 t1 - sin^2 t0| / 2. Few samples
// may fall below the horizon (sampling by radiance alone puts every sample
// there whose direction the normal faces away from).
void expect_exact_irradiance(const LightTable& t, uint32_t seed) {
  const int w = t.sky.width, h = t.sky.height;
  ASSERT_EQ(h % 2, 0) << "the equator must fall between two rows";
  double up[3] = {0, 0, 0}, down[3] = {0, 0, 0};
  for (int y = 0; y < h; ++y) {
    const double t0 = kPi * y / h, t1 = kPi * (y + 1) / h;
    const double band =
        (2 * kPi / w) * std::fabs(std::sin(t1) * std::sin(t1) - std::sin(t0) * std::sin(t0)) / 2;
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) {
        const double l = t.sky_texels[(size_t(y) * size_t(w) + size_t(x)) * 3 + size_t(c)];
        (2 * y < h ? up : down)[c] += l * band;
      }
  }
  auto probe = test::LightProbe::create(t);
  ASSERT_TRUE(probe.is_ok());
  const size_t n = 200000;
  Rng rng(seed);
  std::vector<cl::float4> r(n);
  for (auto& v : r) v = rng.uniform4();
  for (int side = 0; side < 2; ++side) {
    const double sign = side == 0 ? 1 : -1;
    auto s = (*probe)->sample_at({0, 0, 0}, r, {0, float(sign), 0});
    ASSERT_TRUE(s.is_ok());
    size_t below = 0;
    double sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0};
    for (size_t i = 0; i < n; ++i) {
      if (!s->ok(i)) continue;
      const float d = s->wi_pdf[i].x * s->wi_pdf[i].x + s->wi_pdf[i].z * s->wi_pdf[i].z;
      ASSERT_TRUE(std::isfinite(d));
      if (!(sign * s->wi_pdf[i].y > 0)) ++below;
      const double cos = std::max(0.0, sign * s->wi_pdf[i].y);
      const double rad[3] = {s->radiance_dist[i].x, s->radiance_dist[i].y, s->radiance_dist[i].z};
      for (int c = 0; c < 3; ++c) {
        const double v = rad[c] * cos / s->wi_pdf[i].w;
        sum[c] += v;
        sum2[c] += v * v;
      }
    }
    for (int c = 0; c < 3; ++c) {
      const double mean = sum[c] / n, se = std::sqrt(std::max(sum2[c] / n - mean * mean, 0.0) / n);
      const double exact = side == 0 ? up[c] : down[c];
      EXPECT_NEAR(mean, exact, 5 * se + 1e-5 * exact)
          << (side == 0 ? "up" : "down") << " channel " << c;
    }
    EXPECT_LT(double(below) / n, 0.1) << (side == 0 ? "up" : "down");
  }
}

TEST_F(SkyFixture, ImageSkyIrradianceMatchesTheTexelIntegral) {
  test::TempDir d;
  const std::string hdr = d.file("sky.hdr");  // Radiance RGBE, as skies usually come
  ASSERT_TRUE(test::write_rgb_image(hdr, kW, kH, rgb));
  auto t = table(hdr, 30);
  ASSERT_TRUE(t.is_ok()) << t.status().to_string();
  expect_exact_irradiance(t.value(), 22);
}

// A 130 x 70 image is cut into 44 x 24 blocks of 3 x 3 texels; the last
// block column and row reach two texels past the image (weight 0).
TEST_F(SkyFixture, BlocksOfSeveralTexelsWithPaddingSampleTheImageExactly) {
  const int w = 130, h = 70;
  const std::string path = dir.file("large.exr");
  ASSERT_TRUE(test::write_rgb_image(path, w, h, spot_sky(w, h)));
  auto t = table(path, 45);
  ASSERT_TRUE(t.is_ok()) << t.status().to_string();
  EXPECT_EQ(t->sky.block_width, 3);
  EXPECT_EQ(t->sky.block_height, 3);
  EXPECT_EQ(t->sky.blocks_x, 44);
  EXPECT_EQ(t->sky.blocks_y, 24);
  expect_exact_irradiance(t.value(), 23);

  // Sampled directions stay inside the image and MIS reads their pdf back.
  auto probe = test::LightProbe::create(t.value());
  ASSERT_TRUE(probe.is_ok());
  Rng rng(24);
  std::vector<cl::float4> r(50000);
  for (auto& v : r) v = rng.uniform4();
  const Vec3 normal = normalize(Vec3{-0.4f, 0.2f, 0.9f});
  auto s = (*probe)->sample_at({0, 0, 0}, r, normal);
  ASSERT_TRUE(s.is_ok());
  std::vector<cl::float4> dirs;
  for (size_t i = 0; i < r.size(); ++i)
    if (s->ok(i)) dirs.push_back(s->wi_pdf[i]);
  ASSERT_GT(dirs.size(), r.size() * 9 / 10);
  auto again = (*probe)->sky(dirs, normal);
  ASSERT_TRUE(again.is_ok());
  size_t mismatches = 0;
  for (size_t i = 0; i < dirs.size(); ++i)
    if (std::fabs((*again)[i].w / dirs[i].w - 1) > 1e-3) ++mismatches;
  EXPECT_LT(mismatches, dirs.size() / 1000);
}

void expect_sky_error(const Result<LightTable>& t, const std::string& path,
                      const std::string& detail) {
  ASSERT_FALSE(t.is_ok()) << path;
  EXPECT_EQ(t.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(t.status().message().find(path), std::string::npos) << t.status().to_string();
  EXPECT_NE(t.status().message().find(detail), std::string::npos) << t.status().to_string();
}

TEST_F(SkyFixture, BadImagesAreRejectedNamingTheFileAndTexel) {
  auto bad = rgb;
  bad[(size_t(5) * kW + 7) * 3 + 1] = NAN;
  const std::string nan_path = dir.file("nan.exr");
  ASSERT_TRUE(test::write_rgb_image(nan_path, kW, kH, bad));
  expect_sky_error(table(nan_path, 0), nan_path, "texel (7, 5)");

  bad = rgb;
  bad[(size_t(3) * kW + 2) * 3] = -1;
  const std::string neg_path = dir.file("negative.exr");
  ASSERT_TRUE(test::write_rgb_image(neg_path, kW, kH, bad));
  expect_sky_error(table(neg_path, 0), neg_path, "texel (2, 3)");

  const std::string junk = dir.file("junk.hdr");
  std::ofstream(junk) << "this is not an image";
  expect_sky_error(table(junk, 0), junk, "cannot read");
}

TEST_F(SkyFixture, ABlackSkyIsDropped) {
  const std::string black = dir.file("black.exr");
  ASSERT_TRUE(test::write_rgb_image(black, 8, 4, std::vector<float>(8 * 4 * 3, 0.0f)));
  auto t = table(black, 0);
  ASSERT_TRUE(t.is_ok()) << t.status().to_string();
  EXPECT_FALSE(t->has_sky);
  EXPECT_EQ(t->dropped_zero_power, 1u);
  EXPECT_TRUE(t->sky_texels.empty());
  EXPECT_EQ(t->sky.kind, LUX_SKY_KIND_NONE);
}

// The constant sky is sampled cosine-weighted about the receiver's normal:
// in the normal's frame, cos^2 theta and phi are uniform (chi-square over a
// 10 x 12 grid), no sample goes below the surface, and lux_sky_pdf along the
// sampled direction is the sampled pdf, cos / pi (MIS consistency).
TEST(ConstantSky, SamplesTheCosineHemisphereAboutTheNormal) {
  LightSettings settings;
  settings.sky.kind = SkySettings::Kind::kConstant;
  settings.sky.color = {0.2f, 0.4f, 0.8f};
  auto t = build_light_table(scene::Scene{}, accel::TriangleSoup{}, settings, Bounds3{});
  ASSERT_TRUE(t.is_ok()) << t.status().to_string();
  auto probe = test::LightProbe::create(t.value());
  ASSERT_TRUE(probe.is_ok()) << probe.status().to_string();
  const Vec3 n = normalize(Vec3{0.3f, -0.8f, 0.5f});
  const size_t count = 200000;
  Rng rng(31);
  std::vector<cl::float4> r(count);
  for (auto& v : r) v = rng.uniform4();
  auto s = (*probe)->sample_at({1, 2, 3}, r, n);
  ASSERT_TRUE(s.is_ok()) << s.status().to_string();
  // A frame about n for the grid (any will do: phi is uniform).
  const Vec3 a = std::fabs(n.x) > 0.5f ? Vec3{0, 1, 0} : Vec3{1, 0, 0};
  const Vec3 tx = normalize(cross(a, n)), ty = cross(n, tx);
  constexpr int kRows = 10, kCols = 12;
  std::vector<double> observed(kRows * kCols),
      expected(kRows * kCols, double(count) / (kRows * kCols));
  std::vector<cl::float4> dirs;
  std::vector<float> sampled;
  for (size_t i = 0; i < count; ++i) {
    ASSERT_TRUE(s->ok(i));
    ASSERT_TRUE(s->mis(i));
    const Vec3 d = test::xyz(s->wi_pdf[i]);
    const double cos_t = dot(d, n);
    ASSERT_GT(cos_t, 0.0) << "a sky sample below the surface";
    ASSERT_NEAR(s->wi_pdf[i].w, cos_t / kPi, 1e-4 * (1 + cos_t / kPi));
    const double phi = std::atan2(double(dot(d, ty)), double(dot(d, tx))) + kPi;
    const int row = std::min(kRows - 1, int(cos_t * cos_t * kRows));
    const int col = std::min(kCols - 1, int(phi / (2 * kPi) * kCols));
    observed[size_t(row * kCols + col)] += 1;
    if (i < 2000) {
      dirs.push_back(s->wi_pdf[i]);
      sampled.push_back(s->wi_pdf[i].w);
    }
  }
  const auto chi2 = test_support::chi2_test(observed, expected, 1e-4);
  EXPECT_GT(chi2.p_value, 1e-4) << chi2.detail;
  auto pdf = (*probe)->sky(dirs, n);
  ASSERT_TRUE(pdf.is_ok()) << pdf.status().to_string();
  for (size_t k = 0; k < dirs.size(); ++k)
    ASSERT_NEAR((*pdf)[k].w / sampled[k], 1.0, 1e-4) << "direction " << k;
  // Below the surface the pdf is 0: the sky is never sampled there.
  auto below = (*probe)->sky({cl::float4{-n.x, -n.y, -n.z, 0}}, n);
  ASSERT_TRUE(below.is_ok());
  EXPECT_EQ((*below)[0].w, 0.0f);
}

}  // namespace
}  // namespace luxel::pipeline
