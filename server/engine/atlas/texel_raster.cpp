#include "atlas/texel_raster.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "atlas/chart_geometry.h"
#include "kernels/shared/sample_info.h"

namespace luxel::atlas {
namespace {

struct HammersleyTable {
  std::array<double, LUX_SAMPLES_PER_TEXEL> x{}, y{};
  HammersleyTable() {
    for (uint32_t i = 0; i < LUX_SAMPLES_PER_TEXEL; ++i) {
      const cl::float2 p = cl::lux_hammersley64(i);
      x[i] = p.x;
      y[i] = p.y;
    }
  }
};
const HammersleyTable kHammersley;

// Every sample position lies in [0, kLastSample]^2 within its texel.
constexpr double kLastSample = 63.0 / 64.0;

int clamp_to_int(double v, int lo, int hi) {
  return static_cast<int>(std::clamp(v, static_cast<double>(lo), static_cast<double>(hi)));
}

}  // namespace

double hammersley_x(uint32_t i) {
  return kHammersley.x[i];
}
double hammersley_y(uint32_t i) {
  return kHammersley.y[i];
}

TexelTriangle texel_triangle(const scene::Scene& scene, const Atlas& atlas, uint32_t instance,
                             uint32_t triangle) {
  const scene::Mesh& mesh = scene.meshes[static_cast<size_t>(scene.instances[instance].mesh)];
  TexelTriangle t;
  for (int k = 0; k < 3; ++k) {
    const Vec2 uv = atlas.to_atlas(
        instance, mesh.uv1[mesh.indices[size_t{triangle} * 3 + static_cast<size_t>(k)]]);
    t.x[k] = static_cast<double>(uv.x) * atlas.width;
    t.y[k] = static_cast<double>(uv.y) * atlas.height;
  }
  return t;
}

TriangleCoverage::TriangleCoverage(const TexelTriangle& triangle) : t_(triangle) {
  const double* x = t_.x;
  const double* y = t_.y;
  zero_area_ = is_zero_area(x[0], y[0], x[1], y[1], x[2], y[2]);
  const double area2 = (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]);
  const double orientation = area2 >= 0 ? 1.0 : -1.0;
  for (int k = 0; k < 3; ++k) {
    int a = k, b = (k + 1) % 3;
    double sign = orientation;
    if (x[a] > x[b] || (x[a] == x[b] && y[a] > y[b])) {
      std::swap(a, b);
      sign = -sign;
    }
    edges_[k] = {x[a], y[a], x[b] - x[a], y[b] - y[a], sign};
  }
}

void TriangleCoverage::rows(int height, int* begin, int* end) const {
  const double lo = std::min({t_.y[0], t_.y[1], t_.y[2]});
  const double hi = std::max({t_.y[0], t_.y[1], t_.y[2]});
  *begin = clamp_to_int(std::floor(lo), 0, height);
  *end = clamp_to_int(std::floor(hi) + 1, 0, height);
}

void TriangleCoverage::row_span(int y, int width, int* begin, int* end) const {
  const double y0 = y, y1 = y + 1.0;
  double lo = INFINITY, hi = -INFINITY;
  auto include = [&](double x) {
    lo = std::min(lo, x);
    hi = std::max(hi, x);
  };
  for (int k = 0; k < 3; ++k) {
    if (y0 <= t_.y[k] && t_.y[k] <= y1) include(t_.x[k]);
    const int n = (k + 1) % 3;
    const double py = t_.y[k], qy = t_.y[n];
    if (py == qy) continue;
    for (double line : {y0, y1})
      if (std::min(py, qy) <= line && line <= std::max(py, qy))
        include(t_.x[k] + (line - py) * (t_.x[n] - t_.x[k]) / (qy - py));
  }
  if (lo > hi) {
    *begin = *end = 0;
    return;
  }
  *begin = clamp_to_int(std::floor(lo - 1e-6), 0, width);
  *end = clamp_to_int(std::floor(hi + 1e-6) + 1, 0, width);
}

uint64_t TriangleCoverage::texel_mask(int x, int y) const {
  const double x0 = x, y0 = y, x1 = x + kLastSample, y1 = y + kLastSample;
  uint64_t mask = ~uint64_t{0};
  for (const Edge& e : edges_) {
    // The edge function is affine: its values at the corners of the box that
    // holds all 64 positions decide the edge for the whole texel unless they
    // differ in sign. The decision is made from the same canonical values in
    // both triangles of a shared edge, so it stays watertight.
    const double c[4] = {e.eval(x0, y0), e.eval(x1, y0), e.eval(x0, y1), e.eval(x1, y1)};
    const double lo = std::min({c[0], c[1], c[2], c[3]});
    const double hi = std::max({c[0], c[1], c[2], c[3]});
    if (lo >= 0) continue;
    if (hi < 0) return 0;
    uint64_t inside = 0;
    for (uint32_t i = 0; i < LUX_SAMPLES_PER_TEXEL; ++i)
      if (e.eval(x0 + kHammersley.x[i], y0 + kHammersley.y[i]) >= 0) inside |= uint64_t{1} << i;
    mask &= inside;
    if (mask == 0) return 0;
  }
  return mask;
}

}  // namespace luxel::atlas
