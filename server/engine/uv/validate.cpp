#include "uv/validate.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace luxel::uv {
namespace {

constexpr double kZeroAreaSine = 1e-9;

double orient(Vec2 a, Vec2 b, Vec2 c) {
  return (double(b.x) - a.x) * (double(c.y) - a.y) - (double(b.y) - a.y) * (double(c.x) - a.x);
}

struct Segment {
  uint32_t a, b;
  float u_lo, u_hi, v_lo, v_hi;
};

bool boundary_crosses(const std::vector<Vec2>& uv, const std::vector<uint32_t>& indices) {
  std::vector<std::pair<uint32_t, uint32_t>> edges;
  edges.reserve(indices.size());
  for (size_t t = 0; t < indices.size(); t += 3)
    for (int e = 0; e < 3; ++e) {
      const uint32_t p = indices[t + e], q = indices[t + (e + 1) % 3];
      edges.push_back({std::min(p, q), std::max(p, q)});
    }
  std::sort(edges.begin(), edges.end());
  std::vector<Segment> boundary;
  for (size_t i = 0; i < edges.size();) {
    size_t j = i + 1;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    if (j - i == 1) {
      const Vec2 p = uv[edges[i].first], q = uv[edges[i].second];
      boundary.push_back({edges[i].first, edges[i].second, std::min(p.x, q.x), std::max(p.x, q.x),
                          std::min(p.y, q.y), std::max(p.y, q.y)});
    }
    i = j;
  }
  std::sort(boundary.begin(), boundary.end(), [](const Segment& s, const Segment& t) {
    return s.u_lo != t.u_lo ? s.u_lo < t.u_lo : (s.a != t.a ? s.a < t.a : s.b < t.b);
  });
  for (size_t i = 0; i < boundary.size(); ++i) {
    const Segment& s = boundary[i];
    for (size_t j = i + 1; j < boundary.size() && boundary[j].u_lo <= s.u_hi; ++j) {
      const Segment& r = boundary[j];
      if (r.v_lo > s.v_hi || r.v_hi < s.v_lo) continue;
      if (r.a == s.a || r.a == s.b || r.b == s.a || r.b == s.b) continue;
      const double o1 = orient(uv[s.a], uv[s.b], uv[r.a]), o2 = orient(uv[s.a], uv[s.b], uv[r.b]);
      const double o3 = orient(uv[r.a], uv[r.b], uv[s.a]), o4 = orient(uv[r.a], uv[r.b], uv[s.b]);
      if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0)))
        return true;
    }
  }
  return false;
}

}  // namespace

const char* chart_defect_name(ChartDefect defect) {
  switch (defect) {
    case ChartDefect::kNone:
      return "none";
    case ChartDefect::kNonFinite:
      return "non-finite UV";
    case ChartDefect::kZeroArea:
      return "zero-area UV triangle";
    case ChartDefect::kFlipped:
      return "flipped UV triangle";
    case ChartDefect::kBoundaryCrossing:
      return "crossing boundary edges";
  }
  return "?";
}

ChartDefect find_chart_defect(const std::vector<Vec2>& uv, const std::vector<uint32_t>& indices) {
  for (const Vec2& p : uv)
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) return ChartDefect::kNonFinite;
  for (size_t t = 0; t < indices.size(); t += 3) {
    const Vec2 a = uv[indices[t]], b = uv[indices[t + 1]], c = uv[indices[t + 2]];
    const double o = orient(a, b, c);
    auto len2 = [](Vec2 p, Vec2 q) {
      const double dx = double(q.x) - p.x, dy = double(q.y) - p.y;
      return dx * dx + dy * dy;
    };
    const double longest = std::max({len2(a, b), len2(b, c), len2(c, a)});
    if (!(std::fabs(o) > kZeroAreaSine * longest)) return ChartDefect::kZeroArea;
    if (o < 0) return ChartDefect::kFlipped;
  }
  if (boundary_crosses(uv, indices)) return ChartDefect::kBoundaryCrossing;
  return ChartDefect::kNone;
}

ChartDefect validate_chart(const Chart& chart) {
  for (const Vec2& p : chart.uv)  // before sorting: NaN has no order
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) return ChartDefect::kNonFinite;
  // Number chart vertices by distinct UV.
  std::vector<uint32_t> order(chart.uv.size());
  std::iota(order.begin(), order.end(), 0u);
  auto less = [&](uint32_t i, uint32_t j) {
    const Vec2 p = chart.uv[i], q = chart.uv[j];
    return p.x != q.x ? p.x < q.x : (p.y != q.y ? p.y < q.y : i < j);
  };
  std::sort(order.begin(), order.end(), less);
  std::vector<uint32_t> id(chart.uv.size());
  std::vector<Vec2> uv;
  for (size_t k = 0; k < order.size(); ++k) {
    const Vec2 p = chart.uv[order[k]];
    if (uv.empty() || uv.back().x != p.x || uv.back().y != p.y) uv.push_back(p);
    id[order[k]] = static_cast<uint32_t>(uv.size() - 1);
  }
  std::vector<uint32_t> indices(chart.indices.size());
  for (size_t i = 0; i < indices.size(); ++i) indices[i] = id[chart.indices[i]];
  return find_chart_defect(uv, indices);
}

}  // namespace luxel::uv
