// Texel-centre coverage of UV triangles in O(rows) per triangle, shared by
// the scene statistics (scene_stats.h) and the generated layout's overlap
// report (uv/generate.h).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "common/math.h"

namespace luxel::scene {

// Counts, per texel centre of a width x height grid over the unit square,
// the UV triangles added since the last resolve() that contain it. A triangle costs O(rows it
// spans): each row's covered run is found from the edge crossings and recorded as +1/-1 in a
// per-row difference array, resolved by a prefix sum. Counting texel by texel instead costs
// O(area), which random UVs (every triangle about a third of the square) make quadratic in
// practice: 1M such triangles took minutes at 512^2.
class UvRaster {
 public:
  explicit UvRaster(int res) : UvRaster(res, res) {}
  UvRaster(int width, int height)
      : w_(width),
        h_(height),
        diff_(static_cast<size_t>(height) * static_cast<size_t>(width + 1), 0) {}

  void add(Vec2 a, Vec2 b, Vec2 c) {
    const double rx = w_, ry = h_;
    double ax = static_cast<double>(a.x) * rx, ay = static_cast<double>(a.y) * ry;
    double bx = static_cast<double>(b.x) * rx, by = static_cast<double>(b.y) * ry;
    double cx = static_cast<double>(c.x) * rx, cy = static_cast<double>(c.y) * ry;
    const double area = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
    if (!(std::fabs(area) > 0) || !std::isfinite(area)) return;
    if (area < 0) {
      std::swap(bx, cx);
      std::swap(by, cy);
    }
    const double lo_x = std::max(0.0, std::floor(std::min({ax, bx, cx}) - 0.5));
    const double hi_x = std::min(w_ - 1.0, std::ceil(std::max({ax, bx, cx}) - 0.5));
    const double lo_y = std::max(0.0, std::floor(std::min({ay, by, cy}) - 0.5));
    const double hi_y = std::min(h_ - 1.0, std::ceil(std::max({ay, by, cy}) - 0.5));
    if (lo_x > hi_x || lo_y > hi_y) return;
    const Edge edges[3] = {edge(ax, ay, bx, by), edge(bx, by, cx, cy), edge(cx, cy, ax, ay)};
    const int x_lo = static_cast<int>(lo_x), x_hi = static_cast<int>(hi_x);
    for (int y = static_cast<int>(lo_y); y <= static_cast<int>(hi_y); ++y) {
      const double py = y + 0.5;
      // The run from the edge crossings. A crossing within kNear of a centre
      // is settled by the exact per-centre test at the run's ends, so that
      // the result is that of testing every centre (the top-left rule counts
      // a centre on a shared edge once).
      double l = x_lo, h = x_hi;
      bool near = false;
      for (const Edge& e : edges) {
        if (e.dy == 0) {
          const double w = e.dx * (py - e.y0);
          if (w < 0 || (w == 0 && !e.inclusive)) h = l - 1;
          continue;
        }
        // The crossing as a centre index, clamped so that it converts to int
        // (std::floor is a libm call on baseline x86-64; this loop runs
        // once per row of every triangle).
        const double t = std::clamp(e.x0 + e.dx_over_dy * (py - e.y0) - 0.5, -2.0, w_ + 2.0);
        const int ti = static_cast<int>(t + 3.0) - 3;  // floor(t)
        const double frac = t - ti;
        near = near || frac < kNear || frac > 1.0 - kNear;
        if (e.dy > 0) {
          h = std::min(h, static_cast<double>(ti));
        } else {
          l = std::max(l, static_cast<double>(frac > 0 ? ti + 1 : ti));
        }
      }
      int x0 = 0, x1 = 0;
      if (!near) {
        if (l > h) continue;
        x0 = static_cast<int>(l);
        x1 = static_cast<int>(h);
      } else {
        // The exact run lies within one texel of the estimate [l, h].
        const int gl = static_cast<int>(std::clamp<double>(l, x_lo, x_hi + 1.0));
        const int gh = static_cast<int>(std::clamp<double>(h, x_lo - 1.0, x_hi));
        x0 = std::max(gl - 1, x_lo);
        const int end = std::min(gh + 1, x_hi);
        while (x0 <= end && !inside(edges, x0 + 0.5, py)) ++x0;
        if (x0 > end) continue;
        x1 = end;
        while (x1 > x0 && !inside(edges, x1 + 0.5, py)) --x1;
      }
      int32_t* row = &diff_[static_cast<size_t>(y) * static_cast<size_t>(w_ + 1)];
      ++row[x0];
      --row[x1 + 1];
      y_lo_ = std::min(y_lo_, y);
      y_hi_ = std::max(y_hi_, y);
    }
  }

  // Calls f(texel index, count) for every texel with a non-zero count and
  // clears the grid for the next mesh.
  template <class F>
  void resolve(F&& f) {
    for (int y = y_lo_; y <= y_hi_; ++y) {
      int32_t* row = &diff_[static_cast<size_t>(y) * static_cast<size_t>(w_ + 1)];
      int32_t count = 0;
      for (int x = 0; x <= w_; ++x) {
        count += row[x];
        row[x] = 0;
        if (count > 0 && x < w_)
          f(static_cast<size_t>(y) * static_cast<size_t>(w_) + static_cast<size_t>(x), count);
      }
    }
    y_lo_ = h_;
    y_hi_ = -1;
  }

 private:
  // Rounding of a crossing is ~1e-16 of the coordinates (at most w).
  static constexpr double kNear = 1e-6;
  struct Edge {
    double x0, y0, dx, dy, dx_over_dy;
    bool inclusive;
  };
  static Edge edge(double x0, double y0, double x1, double y1) {
    const double dx = x1 - x0, dy = y1 - y0;
    return Edge{x0, y0, dx, dy, dy != 0 ? dx / dy : 0.0, dy < 0 || (dy == 0 && dx < 0)};
  }
  static bool inside(const Edge (&edges)[3], double px, double py) {
    for (const Edge& e : edges) {
      const double w = e.dx * (py - e.y0) - e.dy * (px - e.x0);
      if (w < 0 || (w == 0 && !e.inclusive)) return false;
    }
    return true;
  }

  int w_, h_;
  std::vector<int32_t> diff_;  // h rows of w + 1 entries
  int y_lo_ = h_, y_hi_ = -1;
};

}  // namespace luxel::scene
