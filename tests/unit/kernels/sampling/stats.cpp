#include "stats.h"

#include <algorithm>
#include <numeric>

#include "common/status.h"

namespace luxel::sampling_test {
namespace {

constexpr double kPi = 3.14159265358979323846;
// 5-point Gauss-Legendre rule on [0, 1] (exact for polynomials of degree 9).
constexpr double kGaussNodes[5] = {0.04691007703066800, 0.23076534494715845, 0.5,
                                   0.76923465505284155, 0.95308992296933200};
constexpr double kGaussWeights[5] = {0.11846344252809454, 0.23931433524968324, 0.28444444444444444,
                                     0.23931433524968324, 0.11846344252809454};

}  // namespace

Vec3 spherical_direction(double cos_theta, double phi) {
  const double sin_theta = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta));
  return {sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta};
}

int DirectionBinning::cell(Vec3 d) const {
  double a, b;
  if (!coords(d, &a, &b)) return -1;
  const int ia = std::clamp(int(a * res_a_), 0, res_a_ - 1);
  const int ib = std::clamp(int(b * res_b_), 0, res_b_ - 1);
  return ia * res_b_ + ib;
}

std::vector<DirectionBinning::Node> DirectionBinning::quadrature() const {
  std::vector<Node> nodes;
  nodes.reserve(size_t(cells()) * 25);
  const double cell_area = 1.0 / (double(res_a_) * res_b_);
  for (int ia = 0; ia < res_a_; ++ia)
    for (int ib = 0; ib < res_b_; ++ib)
      for (int i = 0; i < 5; ++i)
        for (int j = 0; j < 5; ++j) {
          double jacobian;
          const Vec3 d =
              direction((ia + kGaussNodes[i]) / res_a_, (ib + kGaussNodes[j]) / res_b_, &jacobian);
          nodes.push_back(
              {d, kGaussWeights[i] * kGaussWeights[j] * cell_area * jacobian, ia * res_b_ + ib});
        }
  return nodes;
}

FocusedAxis::FocusedAxis(double lo, double hi, double center, double width)
    : lo_(lo), hi_(hi), center_(center), width_(width) {
  if (width_ > 0.0) {
    t_lo_ = std::asinh((lo - center) / width);
    t_range_ = std::asinh((hi - center) / width) - t_lo_;
  }
}

double FocusedAxis::value(double a, double* derivative) const {
  if (width_ <= 0.0) {
    *derivative = hi_ - lo_;
    return lo_ + a * (hi_ - lo_);
  }
  const double t = t_lo_ + a * t_range_;
  *derivative = width_ * std::cosh(t) * t_range_;
  return std::clamp(center_ + width_ * std::sinh(t), lo_, hi_);
}

double FocusedAxis::coord(double x) const {
  if (width_ <= 0.0) return (x - lo_) / (hi_ - lo_);
  return (std::asinh((x - center_) / width_) - t_lo_) / t_range_;
}

SphericalBinning SphericalBinning::uniform(int res_a, int res_b, double z_min, double z_max) {
  return SphericalBinning(res_a, res_b, FocusedAxis(z_min, z_max), FocusedAxis(-kPi, kPi));
}

SphericalBinning SphericalBinning::around_mirror(int res_a, int res_b, Vec3 wo, double alpha) {
  const double z = wo.z, sin_theta = std::sqrt(std::max(0.0, 1.0 - z * z));
  const double mirror_phi = std::atan2(-wo.y, -wo.x);
  // alpha^2 keeps a polar width at the pole (wo = normal), where the lobe
  // spans 1 - cos(theta) ~ alpha^2; the azimuth is left uniform there.
  const double z_width = alpha * sin_theta + alpha * alpha;
  const double phi_width = alpha * z / std::max(sin_theta, 1e-6);
  return SphericalBinning(
      res_a, res_b, FocusedAxis(0.0, 1.0, z, z_width),
      phi_width < 1.0 ? FocusedAxis(mirror_phi - kPi, mirror_phi + kPi, mirror_phi, phi_width)
                      : FocusedAxis(mirror_phi - kPi, mirror_phi + kPi));
}

Vec3 SphericalBinning::direction(double a, double b, double* jacobian) const {
  double dz, dphi;
  const double z = cos_theta_.value(a, &dz), phi = phi_.value(b, &dphi);
  *jacobian = dz * dphi;
  return spherical_direction(z, phi);
}

bool SphericalBinning::coords(Vec3 d, double* a, double* b) const {
  // 1 - cos(theta) from the azimuthal components: float z is quantised in
  // steps of 6e-8 near the pole, too coarse for small cones and sharp lobes.
  const double len = length(d);
  const double one_minus_z =
      d.z > 0.0 ? (d.x * d.x + d.y * d.y) / (len * (len + d.z)) : 1.0 - d.z / len;
  const double z = 1.0 - one_minus_z;
  // Float directions may overshoot the range by rounding.
  const double eps = 1e-6 * (cos_theta_.hi() - cos_theta_.lo());
  if (z < cos_theta_.lo() - eps || z > cos_theta_.hi() + eps) return false;
  *a = std::clamp(cos_theta_.coord(std::clamp(z, cos_theta_.lo(), cos_theta_.hi())), 0.0, 1.0);
  double phi = std::atan2(d.y, d.x);
  while (phi < phi_.lo()) phi += 2.0 * kPi;
  while (phi >= phi_.hi()) phi -= 2.0 * kPi;
  *b = std::clamp(phi_.coord(phi), 0.0, 1.0);
  return true;
}

Chi2Outcome directional_chi2(const DirectionBinning& binning,
                             const std::vector<DirectionBinning::Node>& nodes,
                             const std::vector<double>& pdf, const std::vector<Vec3>& samples,
                             size_t total, double significance) {
  LUXEL_CHECK(nodes.size() == pdf.size());
  const int cells = binning.cells();
  std::vector<double> observed(size_t(cells) + 1, 0.0), expected(size_t(cells) + 1, 0.0);
  size_t binned = 0;
  for (const Vec3& s : samples) {
    const int c = binning.cell(s);
    if (c >= 0) observed[size_t(c)] += 1.0, ++binned;
  }
  observed[size_t(cells)] = double(total - binned);
  double integral = 0.0;
  for (size_t i = 0; i < nodes.size(); ++i) {
    const double mass = nodes[i].weight * pdf[i];
    expected[size_t(nodes[i].cell)] += double(total) * mass;
    integral += mass;
  }
  expected[size_t(cells)] = std::max(0.0, double(total) * (1.0 - integral));
  Chi2Outcome out = chi2_test(observed, expected, significance);
  out.detail +=
      strprintf("; density integrates to %.6f, %zu of %zu samples binned", integral, binned, total);
  return out;
}

MeanEstimate estimate_mean(const std::vector<double>& values) {
  MeanEstimate e;
  if (values.empty()) return e;
  const double n = double(values.size());
  e.mean = std::accumulate(values.begin(), values.end(), 0.0) / n;
  double ss = 0.0;
  for (double v : values) ss += (v - e.mean) * (v - e.mean);
  e.standard_error = values.size() > 1 ? std::sqrt(ss / (n - 1.0) / n) : 0.0;
  return e;
}

}  // namespace luxel::sampling_test
