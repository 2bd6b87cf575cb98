// Variance of each texel's mean from two points of its own progressive
// sequence, for the denoiser's luminance weight (post/denoise.h).
//
// The Welford variance of a texel's samples treats them as independent. The
// sequence is stratified (Sobol over the texel's valid sample positions and
// the path dimensions), so for a texel whose positions straddle a shadow
// edge the per-sample variance is large while its mean is accurate: on the
// bundled foliage scene the Welford estimate overstates the squared error of
// the mean 4-10x in most texels, and the denoiser then averages sun-lit
// texels with shadowed ones (docs/accuracy.md "Denoiser").
//
// Instead: keep the mean y_s and count s of each texel at a milestone, and
// at the end (mean y_n, count n) take
//
//   Var(y_n) ~ (y_n - y_s)^2 s / (n - s).
//
// For independent samples y_n - y_s = ((n - s) / n)(y_rest - y_s), whose
// variance is sigma^2 (n - s) / (n s), so the right-hand side has expectation
// sigma^2 / n, the variance of y_n. For a stratified sequence it measures
// how far the mean still moves, which is what its error is: on the foliage
// scene at 64 and 128 spp its sum over texels is within 1 % of the true
// squared error (Welford: 3x; progressive_variance_test: a stratified step
// 2x, Welford 63x). It is a one-degree-of-freedom estimate per texel, noisy
// on its own: the denoiser smooths variances over 3x3 texels of a chart
// before it uses them (kernels/denoise.cl, and its clamp).
//
// Milestones are taken when the tile's mean count doubles (4, 8, 16, ...);
// the last two are kept, and each texel uses the one whose count is nearest
// half its final count among those below it (for independent samples any s
// gives the same chi-square(1) spread; for stratified ones s near n / 2
// compares sets of like size). A texel without a milestone below its
// count (the first iterations, a bake resumed from a checkpoint before its
// next milestone) keeps the Welford variance, as do bakes with the Gaussian
// accumulation filter (weighted samples).
#pragma once

#include <cstdint>
#include <vector>

#include "bake/bake_setup.h"
#include "shards/checkpoint.h"

namespace luxel::pipeline {

class ProgressiveVariance {
 public:
  // Whether a milestone is due at this mean count of the tile.
  bool due(double mean_spp) const;
  // Records the state's luminance means and counts as the newest milestone.
  void record(const BakeCheckpoint& state, double mean_spp);
  // A new tile: its slots start afresh.
  void reset();

  // Variance of the luminance mean of slot `slot` of `state` (the current
  // state of the same tile): the two-point estimate where a milestone below
  // the slot's count exists (then *two_point is set), else the Welford one.
  double slot_variance(const BakeCheckpoint& state, size_t slot, bool* two_point = nullptr) const;

  // Writes the two-point estimates of the tile's covered slots (from
  // `begin`) into `variance` (width * height; resized with -1 when empty);
  // texels without one keep their value. Returns how many it wrote.
  size_t fill(const BakeSetup& setup, const BakeCheckpoint& state, size_t begin,
              std::vector<float>& variance) const;

  // `welford` with every texel that `two_point` holds (>= 0) replaced.
  static std::vector<float> overlay(std::vector<float> welford,
                                    const std::vector<float>& two_point);

  static constexpr double kFirstMilestone = 4;

 private:
  struct Milestone {
    double mean_spp = 0;
    std::vector<float> luminance;
    std::vector<uint32_t> spp;
  };
  Milestone older_, newer_;
};

// The Welford variance of slot `slot`'s luminance mean (var / n_eff);
// 0 with fewer than 2 samples.
double welford_variance(const BakeCheckpoint& state, size_t slot);

}  // namespace luxel::pipeline
