#include "uv/chart_layout.h"

#include <algorithm>
#include <cmath>

namespace luxel::uv {
namespace {

double cross2(DVec2 o, DVec2 a, DVec2 b) {
  return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

// Andrew's monotone chain; counter-clockwise, collinear points dropped.
std::vector<DVec2> convex_hull(std::vector<DVec2> p) {
  std::sort(p.begin(), p.end(),
            [](DVec2 a, DVec2 b) { return a.x != b.x ? a.x < b.x : a.y < b.y; });
  if (p.size() < 3) return p;
  std::vector<DVec2> h(2 * p.size());
  size_t k = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross2(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (size_t i = p.size() - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && cross2(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  h.resize(k - 1);
  return h;
}

}  // namespace

LaidOutChart lay_out_chart(const LocalChart& chart, bool rotate_to_min_rect) {
  double uv_area = 0;
  for (size_t t = 0; t < chart.indices.size(); t += 3)
    uv_area += 0.5 * cross2(chart.uv[chart.indices[t]], chart.uv[chart.indices[t + 1]],
                            chart.uv[chart.indices[t + 2]]);
  const double s = uv_area > 0 ? std::sqrt(chart.area_3d / uv_area) : 1.0;
  std::vector<DVec2> p(chart.uv.size());
  // Relative to the first vertex before scaling, so that large offsets do not
  // cost precision.
  for (size_t i = 0; i < p.size(); ++i)
    p[i] = {(chart.uv[i].x - chart.uv[0].x) * s, (chart.uv[i].y - chart.uv[0].y) * s};

  DVec2 dir{1, 0};  // the new u axis
  if (rotate_to_min_rect) {
    const std::vector<DVec2> hull = convex_hull(p);
    double best = INFINITY;
    for (size_t i = 0; i < hull.size(); ++i) {
      const DVec2 a = hull[i], b = hull[(i + 1) % hull.size()];
      const double l = std::hypot(b.x - a.x, b.y - a.y);
      if (!(l > 0)) continue;
      const DVec2 d{(b.x - a.x) / l, (b.y - a.y) / l};
      double u0 = INFINITY, u1 = -INFINITY, v0 = INFINITY, v1 = -INFINITY;
      for (const DVec2& q : hull) {
        const double u = q.x * d.x + q.y * d.y, v = -q.x * d.y + q.y * d.x;
        u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
      }
      const double area = (u1 - u0) * (v1 - v0);
      if (area < best * (1 - 1e-9)) {  // ties keep the first edge
        best = area;
        dir = (u1 - u0 >= v1 - v0) ? d : DVec2{-d.y, d.x};
      }
    }
  }
  LaidOutChart out;
  double u0 = INFINITY, v0 = INFINITY, u1 = -INFINITY, v1 = -INFINITY;
  for (DVec2& q : p) {
    q = {q.x * dir.x + q.y * dir.y, -q.x * dir.y + q.y * dir.x};
    u0 = std::min(u0, q.x), u1 = std::max(u1, q.x), v0 = std::min(v0, q.y), v1 = std::max(v1, q.y);
  }
  out.uv.resize(p.size());
  for (size_t i = 0; i < p.size(); ++i)
    out.uv[i] = {static_cast<float>(p[i].x - u0), static_cast<float>(p[i].y - v0)};
  out.width = u1 - u0;
  out.height = v1 - v0;
  return out;
}

}  // namespace luxel::uv
