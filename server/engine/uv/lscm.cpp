#include "uv/lscm.h"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>

namespace luxel::uv {

bool solve_lscm(LocalChart& chart) {
  const size_t nv = chart.position.size();
  const size_t nt = chart.indices.size() / 3;
  if (nv < 3) return false;

  DVec3 lo = chart.position[0], hi = chart.position[0];
  for (const DVec3& p : chart.position) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  const DVec3 ext = hi - lo;
  const double scale = std::max({ext.x, ext.y, ext.z});
  if (!(scale > 0)) return false;
  const DVec3 centre = (lo + hi) * 0.5;
  auto local_pos = [&](size_t v) { return (chart.position[v] - centre) * (1.0 / scale); };

  // Pins: the extreme vertices along the longest axis (first index on ties).
  const int axis = (ext.x >= ext.y && ext.x >= ext.z) ? 0 : (ext.y >= ext.z ? 1 : 2);
  auto coord = [&](size_t v) {
    const DVec3 p = chart.position[v];
    return axis == 0 ? p.x : axis == 1 ? p.y : p.z;
  };
  size_t pin0 = 0, pin1 = 0;
  for (size_t v = 1; v < nv; ++v) {
    if (coord(v) < coord(pin0)) pin0 = v;
    if (coord(v) > coord(pin1)) pin1 = v;
  }
  if (pin0 == pin1) return false;
  // Pinned at their distance apart, so the solution has about unit scale.
  const DVec3 dp = local_pos(pin1) - local_pos(pin0);
  const double pin_u[2] = {0.0, std::sqrt(dot(dp, dp))};

  std::vector<int32_t> col(nv, -1);
  int32_t nf = 0;
  for (size_t v = 0; v < nv; ++v)
    if (v != pin0 && v != pin1) col[v] = nf++;

  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(nt * 12);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(2 * nt));
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t* v = &chart.indices[3 * t];
    const DVec3 p0 = local_pos(v[0]), p1 = local_pos(v[1]), p2 = local_pos(v[2]);
    // The triangle in its own orthonormal frame, counter-clockwise.
    const DVec3 e1 = p1 - p0, e2 = p2 - p0;
    const double l1 = std::sqrt(dot(e1, e1));
    const DVec3 x_axis = e1 * (1.0 / l1);
    const DVec3 n = normalize(cross(e1, e2));
    const DVec3 y_axis = cross(n, x_axis);
    const DVec2 z[3] = {{0, 0}, {l1, 0}, {dot(e2, x_axis), dot(e2, y_axis)}};
    const double d_t = z[1].x * z[2].y;  // twice the area
    if (!(d_t > 0)) return false;
    const double w = 1.0 / std::sqrt(d_t);
    // W_j = z_{j+2} - z_{j+1} (eq. 6): sum_j W_j z_j = 0, so the identity
    // (and every orientation-preserving similarity) has zero residual.
    for (int j = 0; j < 3; ++j) {
      const DVec2 a = z[(j + 2) % 3], b = z[(j + 1) % 3];
      const double wr = (a.x - b.x) * w, wi = (a.y - b.y) * w;
      const Eigen::Index re = static_cast<Eigen::Index>(2 * t), im = re + 1;
      // (wr + i wi)(u + i v): real wr u - wi v, imaginary wi u + wr v.
      if (col[v[j]] >= 0) {
        const int32_t cu = col[v[j]], cv = col[v[j]] + nf;
        trip.emplace_back(re, cu, wr);
        trip.emplace_back(re, cv, -wi);
        trip.emplace_back(im, cu, wi);
        trip.emplace_back(im, cv, wr);
      } else {
        const double u = v[j] == pin0 ? pin_u[0] : pin_u[1];  // pinned v is 0
        rhs[re] -= wr * u;
        rhs[im] -= wi * u;
      }
    }
  }
  Eigen::SparseMatrix<double> a(static_cast<Eigen::Index>(2 * nt), 2 * nf);
  a.setFromTriplets(trip.begin(), trip.end());
  const Eigen::SparseMatrix<double> at = a.transpose();
  const Eigen::SparseMatrix<double> normal = at * a;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(normal);
  if (solver.info() != Eigen::Success) return false;
  const Eigen::VectorXd x = solver.solve(at * rhs);
  if (solver.info() != Eigen::Success || !x.allFinite()) return false;

  chart.uv.assign(nv, DVec2{});
  chart.uv[pin0] = {pin_u[0], 0};
  chart.uv[pin1] = {pin_u[1], 0};
  for (size_t v = 0; v < nv; ++v)
    if (col[v] >= 0) chart.uv[v] = {x[col[v]], x[col[v] + nf]};
  return true;
}

}  // namespace luxel::uv
