// Seam stitching: makes the bilinearly filtered lightmap agree on both sides
// of every UV seam (atlas/seams.h), so an engine's texture fetch shows no
// line where a surface edge is cut into two charts.
//
// A least-squares problem over the texels that bilinear fetches along the
// seams read (the 2x2 footprint of every sample point, dilated padding
// included):
//
//   minimise  sum_i d_i (x_i - x0_i)^2  +  lambda sum_s (bilerp_A(s) - bilerp_B(s))^2
//
// x0 are the values as baked (and dilated), d_i the data weight of texel i
// (1 where geometry covers it, `padding_weight` for dilated padding), and s
// runs over sample points spread along each
// seam edge (`samples_per_texel` per texel of the longer side's length), at
// the same edge parameter t on both sides. The normal equations
// (D + lambda R^T R) x = D x0 are sparse, symmetric positive definite, and
// solved by conjugate gradients with a Jacobi preconditioner, for the change
// x - x0 (zero start), on each connected component (texels linked through
// sample points) separately. Every channel is solved on its own with the
// same matrix. Texels outside all footprints keep their values exactly.
//
// Bilinear convention (atlas.h): texel (x, y) covers [x, x+1) x [y, y+1), its
// centre at (x + 0.5, y + 0.5); fetches clamp to the image's edge texels.
// Deterministic (a fixed order of sums, in double).
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <unordered_map>
#include <vector>

#include "common/math.h"

namespace luxel::output {

// One seam edge in texel units of one image: a0 + t (a1 - a0) and
// b0 + t (b1 - b0) are the same surface point for t in [0, 1].
struct StitchEdge {
  Vec2 a0, a1, b0, b1;
  // Width in texels of the narrower chart the seam joins (atlas/seams.h).
  float chart_texels = std::numeric_limits<float>::infinity();
};

struct SeamStitchOptions {
  double seam_weight = 1000;  // lambda
  // d_i of texels no geometry covers. As much as a baked texel: with less
  // (0.1 was tried) the solve swings padding far to satisfy a seam, and
  // fetches just inside the chart see it (the breakfast room went to -4.4
  // W/m^2 where 0.1 let it; docs/accuracy.md "Seam stitching").
  double padding_weight = 1;
  double samples_per_texel = 3;  // sample points per texel of edge length (at least 2 per edge)
  int max_iterations = 2000;     // conjugate-gradient iterations per component and channel
  double tolerance = 1e-6;       // stop at |residual| <= tolerance |rhs| (per component)
  double min_edge_texels = 0;    // seams with a side shorter than this are left alone
  // Seams joining a chart narrower than this (texels) are left alone. In a
  // chart under three texels wide the 2x2 footprints of seams on opposite
  // sides overlap or reach into padding shared with other charts, so the
  // solve moves the whole chart towards its neighbours instead of joining
  // two borders. The breakfast room at 128^2 (4,894 charts, most a few
  // texels): stitching its converged 4096-spp map moved it by RMSE 0.24
  // with no limit, 0.012 with 2 texels and 0.0026 with 3; a 4-second bake
  // stitched with 3 keeps its RMSE (0.0480, 0.24 with no limit).
  // docs/accuracy.md "Seam stitching".
  double min_chart_texels = 3;
  // With a relative standard error per texel (stitch's `rel_error`), a
  // sample point whose two sides differ by more than `structure_sigmas`
  // standard deviations of that difference (the noise cannot explain it)
  // and by more than `structure_rel_gap` times their mean is a
  // discontinuity of the lighting crossing the seam, not a seam artefact,
  // and is left out of the solve: a contact shadow or a buried face meeting
  // the seam at a different texel phase on each side, or a footprint reading
  // padding that dilation filled from a neighbouring chart (charts one texel
  // apart share it). Forcing those to agree moved the gas station's
  // converged 4096-spp map at 128^2 by RMSE 0.092 through 7 seam edges
  // (texels by up to 2.9 W/m^2). Smooth discretisation gaps (relative gap
  // well under 0.5) and noise are still stitched. docs/accuracy.md
  // "Seam stitching".
  double structure_sigmas = 3;
  double structure_rel_gap = 0.5;
  // With `rel_error`, a covered texel also moves at most this many standard
  // errors of its mean: a converged map keeps its baked texels (the stitch
  // then moves padding), a noisy one is stitched as before.
  double max_move_sigmas = 1;
  // That standard error pooled over the texels the texel's sample points
  // read (both sides of the seam) rather than the texel's own, so both sides
  // of a seam may move alike (SeamStitcher::move_reach).
  bool pool_move_sigmas = true;
};

// Size of the difference between the two sides' bilinear values over all
// sample points: per point, the RMS over channels of bilerp_A - bilerp_B
// (abs), and that divided by the RMS over channels of their mean (rel; with
// a floor of 1e-2 times the RMS of all points' means, so near-black regions,
// where noise dominates, do not dominate the figure).
struct SeamDiscontinuity {
  size_t points = 0;
  double rms_abs = 0, max_abs = 0;
  double rms_rel = 0, max_rel = 0;
};

class SeamStitcher {
 public:
  // `coverage`: width * height values, > 0 where geometry covers the texel.
  SeamStitcher(int width, int height, const std::vector<StitchEdge>& edges,
               const std::vector<float>& coverage, const SeamStitchOptions& options = {});

  size_t points() const { return rows_.size(); }
  size_t unknowns() const { return texels_.size(); }
  size_t short_edges() const { return short_edges_; }
  size_t narrow_chart_edges() const { return narrow_chart_edges_; }

  // Stitches channels [first, first + count) of `pixels` (width * height
  // texels of `stride` interleaved channels) in place. Returns the most
  // conjugate-gradient iterations any channel took. With `clamp_negative`
  // solved values below 0 become 0 (for irradiance, which cannot be
  // negative: where seams crowd (charts a few texels wide, footprints read
  // by several seams), the least-squares compromise can undershoot).
  // `rel_error` (width * height, or empty): the relative standard error of
  // each texel's mean (the bake's rel_error); with it, sample points whose
  // gap is structure rather than noise (SeamStitchOptions::structure_sigmas)
  // are left out, decided once from all channels [first, first + count), and
  // their number is added to `*structural` when given.
  int stitch(std::vector<float>& pixels, int stride, int first, int count,
             bool clamp_negative = false, const std::vector<float>& rel_error = {},
             size_t* structural = nullptr) const;

  SeamDiscontinuity measure(const std::vector<float>& pixels, int stride, int first,
                            int count) const;

 private:
  // One sample point: bilerp_A - bilerp_B as up to 8 (unknown, weight) terms.
  struct Row {
    uint32_t unknown[8];
    double weight[8];
    int n = 0;
  };
  void add_sample(Row& row, Vec2 p, double sign);
  uint32_t unknown_of(uint32_t texel);
  // y = (D + lambda R^T R) x
  struct Component {
    uint32_t unknown_begin, unknown_end, row_begin, row_end;
  };
  void split_components();
  // The data term: weights, the normal matrix's diagonal, and t - x0 per
  // unknown (empty: 0, the baked values are the targets).
  struct Weights {
    std::vector<double> data, diagonal, target_shift;
    std::vector<uint8_t> row_on;  // per row; empty: every row
    bool on(uint32_t row) const { return row_on.empty() || row_on[row]; }
  };
  // Rows whose gap is structure, not noise (SeamStitchOptions::structure_sigmas).
  std::vector<uint8_t> noise_rows(const std::vector<float>& pixels, int stride, int first,
                                  int count, const std::vector<float>& rel_error,
                                  size_t& structural) const;
  void apply(const Component& c, const Weights& w, const std::vector<double>& x,
             std::vector<double>& y) const;
  std::vector<double> move_reach(const std::vector<float>& pixels, int stride, int first, int count,
                                 const std::vector<float>& rel_error, const Weights& w) const;
  double texel_rms(const std::vector<float>& pixels, int stride, int first, int count,
                   uint32_t u) const;
  void padding_range(const std::vector<double>& x0, std::vector<double>& lo,
                     std::vector<double>& hi) const;
  int pin_to_bounds(const Weights& base, const std::vector<double>& x0,
                    const std::vector<double>& lo, const std::vector<double>& hi,
                    std::vector<double>& delta, std::vector<double>& r, std::vector<double>& z,
                    std::vector<double>& p, std::vector<double>& q) const;
  int solve(const Component& c, const Weights& w, const std::vector<double>& x0,
            std::vector<double>& delta, std::vector<double>& r, std::vector<double>& z,
            std::vector<double>& p, std::vector<double>& q) const;
  double row_value(const Row& row, const std::vector<double>& x) const;

  int width_, height_;
  SeamStitchOptions options_;
  std::vector<Row> rows_;
  std::vector<uint32_t> texels_;                          // unknown -> texel index
  std::unordered_map<uint32_t, uint32_t> unknown_index_;  // texel -> unknown (construction)
  std::vector<double> data_weight_;                       // per unknown
  std::vector<uint8_t> covered_;                          // per unknown: geometry covers it
  std::vector<double> diagonal_;                          // of the normal matrix, per unknown
  std::vector<Component> components_;
  size_t short_edges_ = 0;         // left alone: a side shorter than min_edge_texels
  size_t narrow_chart_edges_ = 0;  // left alone: a chart narrower than min_chart_texels
};

}  // namespace luxel::output
