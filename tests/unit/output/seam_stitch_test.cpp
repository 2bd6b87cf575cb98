// SeamStitcher on synthetic images with known seams: two charts side by
// side whose shared edge was baked to different values. Bilinear values are
// checked with the test's own bilinear fetch at points other than the
// solver's sample points; the least-squares solution is compared with a
// dense solve of the normal equations built here from the header's
// definition; a seam given with one side reversed must fail the check.
#include "output/seam_stitch.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

namespace luxel::output {
namespace {

struct Img {
  int w, h, c;
  std::vector<float> px;
  float at(int x, int y, int ch) const { return px[(size_t(y) * w + x) * c + ch]; }
};

// Bilinear fetch, texel centres at +0.5, clamped to the edge (atlas.h).
double bilerp(const Img& img, double px, double py, int ch) {
  const double sx = px - 0.5, sy = py - 0.5;
  const int x0 = int(std::floor(sx)), y0 = int(std::floor(sy));
  const double fx = sx - x0, fy = sy - y0;
  auto t = [&](int x, int y) {
    return double(img.at(std::clamp(x, 0, img.w - 1), std::clamp(y, 0, img.h - 1), ch));
  };
  return (1 - fy) * ((1 - fx) * t(x0, y0) + fx * t(x0 + 1, y0)) +
         fy * ((1 - fx) * t(x0, y0 + 1) + fx * t(x0 + 1, y0 + 1));
}

// Largest |bilerp_A - bilerp_B| / mean along the edges at 41 points each.
double worst_relative_gap(const Img& img, const std::vector<StitchEdge>& edges, int ch) {
  double worst = 0;
  for (const StitchEdge& e : edges)
    for (int k = 0; k <= 40; ++k) {
      const double t = k / 40.0;
      const double a =
          bilerp(img, e.a0.x + t * (e.a1.x - e.a0.x), e.a0.y + t * (e.a1.y - e.a0.y), ch);
      const double b =
          bilerp(img, e.b0.x + t * (e.b1.x - e.b0.x), e.b0.y + t * (e.b1.y - e.b0.y), ch);
      worst = std::max(worst, std::abs(a - b) / (0.5 * (std::abs(a) + std::abs(b)) + 1e-9));
    }
  return worst;
}

// Two 4-texel-wide charts, x in [1, 5) and [7, 11), rows [1, 9): the left
// chart's right border (x = 5) and the right chart's left border (x = 7)
// are one surface edge, running in the same direction. Left values 1 + y/8,
// right 2 + y/4 (a gradient along the edge, so reversing one side matters);
// padding one texel wide (coverage 0) copies the neighbouring chart texel.
Img two_charts(std::vector<float>& coverage) {
  Img img{12, 10, 2, {}};
  img.px.assign(size_t(img.w) * img.h * img.c, 0.0f);
  coverage.assign(size_t(img.w) * img.h, 0.0f);
  for (int y = 0; y < img.h; ++y)
    for (int x = 0; x < img.w; ++x) {
      const int yc = std::clamp(y, 1, 8);
      const bool left = x <= 5, covered = (x >= 1 && x < 5) || (x >= 7 && x < 11);
      const float v = left ? 1.0f + yc / 8.0f : 2.0f + yc / 4.0f;
      const size_t i = size_t(y) * img.w + x;
      img.px[i * 2] = v;
      img.px[i * 2 + 1] = 10.0f * v;  // a second channel, 10x: solved on its own
      coverage[i] = covered && y >= 1 && y < 9 ? 1.0f : 0.0f;
    }
  return img;
}

const std::vector<StitchEdge> kEdge = {{{5, 1}, {5, 9}, {7, 1}, {7, 9}}};

TEST(SeamStitch, BilinearValuesAgreeAlongTheSeamAfterStitching) {
  std::vector<float> coverage;
  Img img = two_charts(coverage);
  const Img before = img;
  const SeamStitcher stitcher(img.w, img.h, kEdge, coverage);
  EXPECT_GT(worst_relative_gap(img, kEdge, 0), 0.3);
  const SeamDiscontinuity d0 = stitcher.measure(img.px, 2, 0, 2);
  stitcher.stitch(img.px, 2, 0, 2);
  const SeamDiscontinuity d1 = stitcher.measure(img.px, 2, 0, 2);
  for (int ch = 0; ch < 2; ++ch) EXPECT_LT(worst_relative_gap(img, kEdge, ch), 0.01) << ch;
  EXPECT_GT(d0.max_rel, 0.3);
  EXPECT_LT(d1.max_rel, 0.01);
  EXPECT_LT(d1.rms_abs, d0.rms_abs / 50);
  // The second channel is the first times 10: so is its solution.
  for (size_t i = 0; i < img.px.size(); i += 2)
    EXPECT_NEAR(img.px[i + 1], 10.0f * img.px[i], 1e-4f * std::abs(img.px[i + 1]) + 1e-5f);
  // Texels no fetch along the seam reads (x outside 4..7) keep their bits.
  for (int y = 0; y < img.h; ++y)
    for (int x = 0; x < img.w; ++x)
      if (x < 4 || x > 7)
        for (int ch = 0; ch < 2; ++ch) EXPECT_EQ(img.at(x, y, ch), before.at(x, y, ch));
  // A point one texel row away from both borders (x = 2.5, 9.5) is unchanged.
  EXPECT_DOUBLE_EQ(bilerp(img, 2.5, 4.5, 0), bilerp(before, 2.5, 4.5, 0));
}

// The same seam, but one of its charts is narrower than min_chart_texels:
// it is left alone (no unknowns, every texel keeps its bits) and counted; at
// the chart width of two_charts (4 texels) it is stitched as above.
TEST(SeamStitch, SeamsOfNarrowChartsAreLeftAlone) {
  std::vector<float> coverage;
  Img img = two_charts(coverage);
  const Img before = img;
  std::vector<StitchEdge> narrow = kEdge;
  narrow[0].chart_texels = 1.5f;
  const SeamStitcher skip(img.w, img.h, narrow, coverage);
  EXPECT_EQ(skip.narrow_chart_edges(), 1u);
  EXPECT_EQ(skip.points(), 0u);
  EXPECT_EQ(skip.unknowns(), 0u);
  skip.stitch(img.px, 2, 0, 2);
  EXPECT_EQ(img.px, before.px);
  std::vector<StitchEdge> wide = kEdge;
  wide[0].chart_texels = 4.0f;
  const SeamStitcher stitch(img.w, img.h, wide, coverage);
  EXPECT_EQ(stitch.narrow_chart_edges(), 0u);
  stitch.stitch(img.px, 2, 0, 2);
  EXPECT_LT(worst_relative_gap(img, kEdge, 0), 0.01);
  // The limit is an option: 0 stitches every chart.
  SeamStitchOptions all;
  all.min_chart_texels = 0;
  EXPECT_EQ(SeamStitcher(img.w, img.h, narrow, coverage, all).narrow_chart_edges(), 0u);
}

// A black region (x <= 5) against a lit one (x >= 6), with a seam whose two
// sides both read texel column 5 (x = 4.6 reads columns 4 and 5, x = 5.9
// columns 5 and 6): raising side A's mean to side B's pulls column 5 down,
// below 0. With clamp_negative those texels are pinned at 0 and re-solved:
// nothing ends below 0 and the sides still agree.
TEST(SeamStitch, ClampedStitchIsNonNegativeAndAgrees) {
  const int w = 10, h = 10;
  Img img{w, h, 1, std::vector<float>(size_t(w) * h)};
  std::vector<float> coverage(size_t(w) * h, 1.0f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img.px[size_t(y) * w + x] = x <= 5 ? 0.0f : 1.0f + y / 4.0f;
  const std::vector<StitchEdge> edges = {{{4.6f, 1}, {4.6f, 9}, {5.9f, 1}, {5.9f, 9}}};
  const SeamStitcher stitcher(w, h, edges, coverage);
  Img unclamped = img;
  stitcher.stitch(unclamped.px, 1, 0, 1);
  stitcher.stitch(img.px, 1, 0, 1, true);
  const float lowest_unclamped = *std::min_element(unclamped.px.begin(), unclamped.px.end());
  EXPECT_LT(lowest_unclamped, -0.1f);  // the undershoot the clamp exists for
  EXPECT_EQ(*std::min_element(img.px.begin(), img.px.end()), 0.0f);
  EXPECT_LT(worst_relative_gap(unclamped, edges, 0), 0.01);
  EXPECT_LT(worst_relative_gap(img, edges, 0), 0.01);
}

// The gas station's cause, in small: two charts of one flat floor, 16 x 16
// each, one seam along their shared edge (x = 8 in chart A, x = 24 in chart
// B, the same y). Another object stands on the floor and buries part of it,
// so the converged irradiance steps from 6 to 0 along the seam; the step
// lies at y = 8 in A and, at a different texel phase, in the middle of texel
// row 8 in B (half its texels under the object). The bilinear fetches of
// the two sides then differ by up to 3 near the step, by structure, not
// noise. The map is converged: relative standard error 1e-3.
TEST(SeamStitch, ConvergedMapMovesNoMoreThanItsNoise) {
  const int w = 32, h = 16;
  std::vector<float> coverage(size_t(w) * h, 0.0f);
  Img img{w, h, 1, std::vector<float>(size_t(w) * h, 0.0f)};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t t = size_t(y) * w + x;
      if (x < 8) img.px[t] = y < 8 ? 6.0f : 0.0f;                    // chart A, step at y = 8
      if (x >= 24) img.px[t] = y < 8 ? 6.0f : y == 8 ? 3.0f : 0.0f;  // chart B, at 8.5
      coverage[t] = (x < 8 || x >= 24) ? 1.0f : 0.0f;
      if (x == 8 || x == 23) img.px[t] = y < 8 ? 6.0f : 0.0f;  // dilated padding
    }
  const std::vector<StitchEdge> edges = {{{8, 0}, {8, 16}, {24, 0}, {24, 16}}};
  const std::vector<float> rel_error(size_t(w) * h, 1e-3f);
  const SeamStitcher stitcher(w, h, edges, coverage);
  const Img baked = img;
  double largest_unbounded = 0, largest = 0;
  Img unbounded = img;
  stitcher.stitch(unbounded.px, 1, 0, 1, true);  // as before: every gap closed
  size_t structural = 0;
  stitcher.stitch(img.px, 1, 0, 1, true, rel_error, &structural);
  for (size_t t = 0; t < img.px.size(); ++t) {
    if (!(coverage[t] > 0)) continue;
    largest_unbounded =
        std::max(largest_unbounded, double(std::abs(unbounded.px[t] - baked.px[t])));
    largest = std::max(largest, double(std::abs(img.px[t] - baked.px[t])));
    // One standard error (SeamStitchOptions::max_move_sigmas), pooled over
    // the texels the texel's sample points read: at most 1e-3 x 6, and none
    // where all of them are dark (rows 10 and below: the step's footprints
    // end at row 9).
    EXPECT_LE(std::abs(img.px[t] - baked.px[t]), 1e-3 * 6.0 + 1e-6) << t;
    if (t / w >= 10) EXPECT_LE(std::abs(img.px[t] - baked.px[t]), 1e-6) << t;
  }
  std::printf("largest move of a covered texel: %.4g unbounded, %.4g with rel_error\n",
              largest_unbounded, largest);
  EXPECT_GT(largest_unbounded, 0.5);  // what moved the gas station's converged map
  EXPECT_GT(structural, 0u);          // the points at the step are left out
  // Away from the step both sides agree already, and the padding still
  // makes the seam's fetches agree there: the stitch is not switched off.
  EXPECT_LT(std::abs(bilerp(img, 8, 3, 0) - bilerp(img, 24, 3, 0)), 1e-3);
}

// A noisy bake of a uniformly lit floor split into two charts (the geometry
// above, irradiance 1 everywhere). Each texel is the mean of 16 samples of a
// skewed estimator, 0.5 with probability 0.9 and 5.5 with 0.1 (mean 1), as a
// few bright paths make a texel's mean at low sample counts; rel_error is
// each texel's own estimate, as the bake gives it. A texel that drew a bright
// sample has a wide spread, one that drew none has none, so its own standard
// error follows its value. Over 400 such maps the stitch must keep the mean
// of the texels its sample points read, within 4 standard errors of the
// maps' spread: the seam is as bright as the rest of the floor. (Pooled, the
// bounds of a seam's two sides are alike and this geometry's solve keeps the
// sum exactly; the absolute 1e-4 is for rounding.) Returns the mean change
// and its standard error.
struct MeanShift {
  double mean, stderr_;
};
MeanShift noisy_floor_mean_shift(bool pool) {
  const int w = 32, h = 16, n = 16, maps = 400;
  std::vector<float> coverage(size_t(w) * h, 0.0f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) coverage[size_t(y) * w + x] = (x < 8 || x >= 24) ? 1.0f : 0.0f;
  const std::vector<StitchEdge> edges = {{{8, 0}, {8, 16}, {24, 0}, {24, 16}}};
  SeamStitchOptions o;
  o.pool_move_sigmas = pool;
  const SeamStitcher stitcher(w, h, edges, coverage, o);
  std::mt19937 rng(12345);
  std::bernoulli_distribution bright(0.1);
  double sum = 0, sum2 = 0;
  for (int m = 0; m < maps; ++m) {
    Img img{w, h, 1, std::vector<float>(size_t(w) * h, 0.0f)};
    std::vector<float> rel(size_t(w) * h, 0.0f);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        if (!(x < 8 || x >= 24)) continue;
        double s = 0, s2 = 0;
        for (int k = 0; k < n; ++k) {
          const double v = bright(rng) ? 5.5 : 0.5;
          s += v;
          s2 += v * v;
        }
        const double mean = s / n, var = std::max(0.0, (s2 - s * s / n) / (n - 1));
        img.px[size_t(y) * w + x] = float(mean);
        rel[size_t(y) * w + x] = float(std::sqrt(var / n) / mean);
      }
    for (int y = 0; y < h; ++y) {  // one texel of dilated padding each side
      img.px[size_t(y) * w + 8] = img.px[size_t(y) * w + 7];
      img.px[size_t(y) * w + 23] = img.px[size_t(y) * w + 24];
    }
    const Img before = img;
    stitcher.stitch(img.px, 1, 0, 1, true, rel);
    double shift = 0;
    int texels = 0;
    for (int y = 0; y < h; ++y)
      for (int x : {6, 7, 24, 25}) {  // the covered texels the seam's points read
        shift += img.px[size_t(y) * w + x] - before.px[size_t(y) * w + x];
        ++texels;
      }
    shift /= texels;
    sum += shift;
    sum2 += shift * shift;
  }
  const double mean = sum / maps;
  return {mean, std::sqrt(std::max(0.0, sum2 / maps - mean * mean) / (maps - 1))};
}

TEST(SeamStitch, NoisyMapKeepsItsMeanAtTheSeam) {
  const MeanShift pooled = noisy_floor_mean_shift(true);
  std::printf("mean change at the seam, pooled standard errors: %+.5f +- %.5f\n", pooled.mean,
              pooled.stderr_);
  EXPECT_LT(std::abs(pooled.mean), 4 * pooled.stderr_ + 1e-4);
  // Injected error: each texel bounded by its own standard error (the stitch
  // before pooling) darkens the seam, and the same check must fail.
  const MeanShift own = noisy_floor_mean_shift(false);
  std::printf("mean change at the seam, own standard errors: %+.5f +- %.5f\n", own.mean,
              own.stderr_);
  EXPECT_LT(own.mean, -4 * own.stderr_ - 1e-4);
}

TEST(SeamStitch, ReversedSideFailsTheAgreementCheck) {
  std::vector<float> coverage;
  Img img = two_charts(coverage);
  // Injected error: side B given from its other end.
  const std::vector<StitchEdge> reversed = {{{5, 1}, {5, 9}, {7, 9}, {7, 1}}};
  const SeamStitcher stitcher(img.w, img.h, reversed, coverage);
  stitcher.stitch(img.px, 2, 0, 2);
  EXPECT_GT(worst_relative_gap(img, kEdge, 0), 0.05);
}

// Gaussian elimination with partial pivoting on a dense symmetric system.
std::vector<double> dense_solve(std::vector<std::vector<double>> a, std::vector<double> b) {
  const size_t n = b.size();
  for (size_t k = 0; k < n; ++k) {
    size_t piv = k;
    for (size_t i = k + 1; i < n; ++i)
      if (std::abs(a[i][k]) > std::abs(a[piv][k])) piv = i;
    std::swap(a[k], a[piv]);
    std::swap(b[k], b[piv]);
    for (size_t i = k + 1; i < n; ++i) {
      const double f = a[i][k] / a[k][k];
      for (size_t j = k; j < n; ++j) a[i][j] -= f * a[k][j];
      b[i] -= f * b[k];
    }
  }
  std::vector<double> x(n);
  for (size_t k = n; k-- > 0;) {
    double s = b[k];
    for (size_t j = k + 1; j < n; ++j) s -= a[k][j] * x[j];
    x[k] = s / a[k][k];
  }
  return x;
}

// A tiny 7 x 5 image with a slanted seam: the stitched image equals the
// dense least-squares solution of (D + lambda R^T R) x = D x0, with R built
// here from bilinear weights at the documented sample points.
TEST(SeamStitch, MatchesADenseLeastSquaresSolve) {
  const int w = 7, h = 5;
  Img img{w, h, 1, std::vector<float>(size_t(w) * h)};
  std::vector<float> coverage(size_t(w) * h);
  for (int i = 0; i < w * h; ++i) {
    img.px[i] = float(std::sin(1.3 * i) + 2.0);
    coverage[i] = (i % 3) ? 1.0f : 0.0f;
  }
  const std::vector<StitchEdge> edges = {{{1.2f, 0.7f}, {2.9f, 4.1f}, {5.6f, 4.3f}, {4.4f, 1.1f}}};
  SeamStitchOptions o;
  o.seam_weight = 30;
  o.padding_weight = 0.25;
  o.tolerance = 1e-13;
  const size_t n = size_t(w) * h;
  std::vector<std::vector<double>> a(n, std::vector<double>(n, 0.0));
  std::vector<double> b(n);
  for (size_t i = 0; i < n; ++i) {
    const double d = coverage[i] > 0 ? 1.0 : o.padding_weight;
    a[i][i] = d;
    b[i] = d * img.px[i];
  }
  const StitchEdge& e = edges[0];
  const double len = std::max(std::hypot(e.a1.x - e.a0.x, e.a1.y - e.a0.y),
                              std::hypot(e.b1.x - e.b0.x, e.b1.y - e.b0.y));
  const int points = std::max(2, int(std::ceil(o.samples_per_texel * len)));
  for (int k = 0; k < points; ++k) {
    const double t = (k + 0.5) / points;
    std::vector<double> row(n, 0.0);
    auto add = [&](double px, double py, double sign) {
      const double sx = px - 0.5, sy = py - 0.5;
      const int x0 = int(std::floor(sx)), y0 = int(std::floor(sy));
      const double fx = sx - x0, fy = sy - y0;
      for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i)
          row[size_t(std::clamp(y0 + j, 0, h - 1)) * w + std::clamp(x0 + i, 0, w - 1)] +=
              sign * (i ? fx : 1 - fx) * (j ? fy : 1 - fy);
    };
    add(e.a0.x + t * (e.a1.x - e.a0.x), e.a0.y + t * (e.a1.y - e.a0.y), 1);
    add(e.b0.x + t * (e.b1.x - e.b0.x), e.b0.y + t * (e.b1.y - e.b0.y), -1);
    for (size_t i = 0; i < n; ++i)
      for (size_t j = 0; j < n; ++j) a[i][j] += o.seam_weight * row[i] * row[j];
  }
  const std::vector<double> want = dense_solve(a, b);
  SeamStitcher(w, h, edges, coverage, o).stitch(img.px, 1, 0, 1);
  for (size_t i = 0; i < n; ++i) EXPECT_NEAR(img.px[i], want[i], 2e-6) << i;
}

// Channels go to threads; a channel's result must not depend on which.
TEST(SeamStitch, SameBitsForAnyChannelGrouping) {
  std::vector<float> coverage;
  Img img = two_charts(coverage);
  Img one_by_one = img;
  const SeamStitcher stitcher(img.w, img.h, kEdge, coverage);
  stitcher.stitch(img.px, 2, 0, 2);
  stitcher.stitch(one_by_one.px, 2, 1, 1);
  stitcher.stitch(one_by_one.px, 2, 0, 1);
  EXPECT_EQ(img.px, one_by_one.px);
}

TEST(SeamStitch, NoSeamsChangesNothing) {
  std::vector<float> coverage;
  Img img = two_charts(coverage);
  const Img before = img;
  const SeamStitcher stitcher(img.w, img.h, {}, coverage);
  EXPECT_EQ(stitcher.stitch(img.px, 2, 0, 2), 0);
  EXPECT_EQ(img.px, before.px);
  EXPECT_EQ(stitcher.measure(img.px, 2, 0, 2).points, 0u);
}

}  // namespace
}  // namespace luxel::output
