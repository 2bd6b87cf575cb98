// Statistics for the sampling tests: chi-square goodness of fit of sampled
// directions against a density (the test itself is tests/support/chi2.h,
// shared with the shading tests), direction binnings with their Jacobians,
// and small vector helpers.
//
// A chi-square case bins N samples into cells of a partition of the domain;
// the expected count of a cell is N times the density integrated over the
// cell (Gauss-Legendre quadrature, 5x5 nodes per cell, of the density the
// device reports). Cells expected to hold fewer than 5 samples are pooled.
// Samples outside the binned domain (or rejected by the sampler) form one
// extra cell expecting N - sum(expected), so a density that does not
// integrate to what the sampler delivers fails too (the pooling rule is
// chi2_test's).
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "kernels/shared/compat.h"
#include "support/chi2.h"

namespace luxel::sampling_test {

// Family-wise significance of every test that runs several chi-square
// cases; each case is held to kFamilySignificance / cases (Bonferroni).
inline constexpr double kFamilySignificance = 1e-4;

struct Vec3 {
  double x = 0, y = 0, z = 0;
};
inline Vec3 operator+(Vec3 a, Vec3 b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
inline Vec3 operator-(Vec3 a, Vec3 b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline Vec3 operator*(double s, Vec3 a) {
  return {s * a.x, s * a.y, s * a.z};
}
inline double dot(Vec3 a, Vec3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double length(Vec3 a) {
  return std::sqrt(dot(a, a));
}
inline Vec3 normalize(Vec3 a) {
  return (1.0 / length(a)) * a;
}
inline Vec3 to_vec3(const cl::float4& v) {
  return {v.x, v.y, v.z};
}
inline cl::float4 to_float4(Vec3 v, float w = 0.0f) {
  return {float(v.x), float(v.y), float(v.z), w};
}
// Unit direction with polar cosine cos_theta and azimuth phi.
Vec3 spherical_direction(double cos_theta, double phi);

using test_support::chi2_test;
using test_support::chi2_upper_tail;
using test_support::Chi2Outcome;

// A partition of a set of directions into res_a x res_b cells through a map
// from [0,1)^2 onto the set.
class DirectionBinning {
 public:
  DirectionBinning(int res_a, int res_b) : res_a_(res_a), res_b_(res_b) {}
  virtual ~DirectionBinning() = default;
  int cells() const { return res_a_ * res_b_; }
  // The direction at (a, b) and |d omega / (da db)|.
  virtual Vec3 direction(double a, double b, double* jacobian) const = 0;
  // Inverse map; false outside the binned set.
  virtual bool coords(Vec3 d, double* a, double* b) const = 0;
  // Cell of d, or -1 outside.
  int cell(Vec3 d) const;

  // Quadrature nodes of all cells: direction, weight (so that the integral
  // of g over cell c is the sum of weight * g(direction) over its nodes) and
  // the cell.
  struct Node {
    Vec3 dir;
    double weight;
    int cell;
  };
  std::vector<Node> quadrature() const;

 protected:
  int res_a_, res_b_;
};

// A monotone map of [0, 1] onto [lo, hi]: uniform, or graded around
// `center`: x = center + width sinh(t) with t linear in a, so cells have size
// ~width near the centre and grow geometrically away from it. The Jacobian
// is smooth at the scale of a cell, which keeps per-cell quadrature accurate
// for sharp lobes and broad densities alike.
class FocusedAxis {
 public:
  FocusedAxis(double lo, double hi) : FocusedAxis(lo, hi, 0.0, 0.0) {}
  FocusedAxis(double lo, double hi, double center, double width);
  // x(a) and dx/da.
  double value(double a, double* derivative) const;
  // a(x), the inverse.
  double coord(double x) const;
  double lo() const { return lo_; }
  double hi() const { return hi_; }

 private:
  double lo_, hi_, center_, width_, t_lo_ = 0, t_range_ = 0;
};

// Directions binned by cos(theta) (a) and azimuth (b), each axis a
// FocusedAxis. The azimuth axis spans some [c - pi, c + pi).
// Any discontinuity of a density at the horizon falls on a cell edge when the
// cos(theta) range starts at 0, so quadrature only meets smooth integrands.
class SphericalBinning : public DirectionBinning {
 public:
  SphericalBinning(int res_a, int res_b, FocusedAxis cos_theta, FocusedAxis phi)
      : DirectionBinning(res_a, res_b), cos_theta_(cos_theta), phi_(phi) {}
  // Uniform cells over cos(theta) in [z_min, z_max].
  static SphericalBinning uniform(int res_a, int res_b, double z_min, double z_max);
  // Upper hemisphere, with cells concentrated around the mirror direction of
  // wo, where a GGX lobe of roughness alpha reflects. The widths follow the
  // reflection geometry: polar spread ~ alpha sin(theta), azimuthal spread
  // ~ alpha cos(theta) / sin(theta) (narrow at grazing incidence).
  static SphericalBinning around_mirror(int res_a, int res_b, Vec3 wo, double alpha);
  Vec3 direction(double a, double b, double* jacobian) const override;
  bool coords(Vec3 d, double* a, double* b) const override;

 private:
  FocusedAxis cos_theta_, phi_;
};

// Chi-square case over a binning: `samples` are the directions the sampler
// produced (rejected samples are simply absent: they count against the
// outside cell), `pdf` the density at each quadrature node, in the order of
// binning.quadrature(). `total` is the number of attempts.
Chi2Outcome directional_chi2(const DirectionBinning& binning,
                             const std::vector<DirectionBinning::Node>& nodes,
                             const std::vector<double>& pdf, const std::vector<Vec3>& samples,
                             size_t total, double significance);

// Mean and standard error of the mean.
struct MeanEstimate {
  double mean = 0, standard_error = 0;
};
MeanEstimate estimate_mean(const std::vector<double>& values);

}  // namespace luxel::sampling_test
