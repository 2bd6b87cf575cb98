#include "atlas/shelf_packer.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>

namespace luxel::atlas {
namespace {

// Rectangles beyond this side are "too large" without further arithmetic
// (keeps int conversions defined for absurd densities).
constexpr double kMaxRectSide = 1 << 24;

double texels_per_uv(const ChartExtent& c, double density) {
  if (c.stretch > 0) return density * c.stretch;
  // No world area: half a texel across, so the rectangle is 1 x 1.
  return 0.5 / std::max(c.uv_width, c.uv_height);
}

// Rectangle sizes at `density`; false when one would exceed kMaxRectSide.
bool chart_sizes(const std::vector<ChartExtent>& charts, double density,
                 std::vector<std::array<int, 2>>* sizes) {
  sizes->resize(charts.size());
  for (size_t i = 0; i < charts.size(); ++i) {
    const double s = texels_per_uv(charts[i], density);
    const double w = std::floor(charts[i].uv_width * s + 2 * kChartInsetTexels) + 1;
    const double h = std::floor(charts[i].uv_height * s + 2 * kChartInsetTexels) + 1;
    if (!(w <= kMaxRectSide && h <= kMaxRectSide)) return false;
    (*sizes)[i] = {static_cast<int>(w), static_cast<int>(h)};
  }
  return true;
}

bool fits(const std::vector<ChartExtent>& charts, double density, int side, int padding) {
  std::vector<std::array<int, 2>> sizes;
  return chart_sizes(charts, density, &sizes) && !shelf_pack(sizes, side, padding).empty();
}

PackedLayout make_layout(const std::vector<ChartExtent>& charts, double density, int side,
                         int padding) {
  PackedLayout layout;
  layout.side = side;
  layout.density = density;
  std::vector<std::array<int, 2>> sizes;
  LUXEL_CHECK(chart_sizes(charts, density, &sizes));
  const auto positions = shelf_pack(sizes, side, padding);
  LUXEL_CHECK(positions.size() == charts.size());
  for (size_t i = 0; i < charts.size(); ++i) {
    layout.texels_per_uv.push_back(texels_per_uv(charts[i], density));
    layout.rects.push_back({positions[i][0], positions[i][1], sizes[i][0], sizes[i][1]});
  }
  return layout;
}

int round_up_to_4(double v) {
  return static_cast<int>(std::ceil(v / 4.0)) * 4;
}

}  // namespace

std::vector<std::array<int, 2>> shelf_pack(const std::vector<std::array<int, 2>>& sizes, int side,
                                           int padding) {
  std::vector<size_t> order(sizes.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    if (sizes[a][1] != sizes[b][1]) return sizes[a][1] > sizes[b][1];
    return sizes[a][0] > sizes[b][0];
  });
  std::vector<std::array<int, 2>> positions(sizes.size());
  int64_t x = padding, y = padding, shelf_height = 0;
  for (size_t i : order) {
    const int64_t w = sizes[i][0], h = sizes[i][1];
    if (x + w + padding > side) {  // next shelf
      y += shelf_height + padding;
      x = padding;
      shelf_height = 0;
    }
    if (x + w + padding > side || y + h + padding > side) return {};
    positions[i] = {static_cast<int>(x), static_cast<int>(y)};
    x += w + padding;
    shelf_height = std::max(shelf_height, h);
  }
  return positions;
}

Result<PackedLayout> pack_at_resolution(const std::vector<ChartExtent>& charts, int side,
                                        int padding) {
  if (!fits(charts, 0.0, side, padding))
    return resource_exhausted(strprintf(
        "%zu lightmap charts (one per instance) do not fit in a %dx%d atlas with %d texels of "
        "padding even at one texel each; raise --resolution, or bake with --uv generate",
        charts.size(), side, side, padding));
  // Upper bound: at hi the rectangles' total area alone exceeds side^2.
  double area_per_density2 = 0;
  for (const auto& c : charts)
    area_per_density2 += c.uv_width * c.uv_height * c.stretch * c.stretch;
  if (!(area_per_density2 > 0)) return make_layout(charts, 0.0, side, padding);
  double lo = 0, hi = side / std::sqrt(area_per_density2);
  for (int iteration = 0; iteration < 64; ++iteration) {
    const double mid = 0.5 * (lo + hi);
    (fits(charts, mid, side, padding) ? lo : hi) = mid;
  }
  return make_layout(charts, lo, side, padding);
}

Result<PackedLayout> pack_at_density(const std::vector<ChartExtent>& charts, double density,
                                     int padding, int max_side) {
  std::vector<std::array<int, 2>> sizes;
  if (!chart_sizes(charts, density, &sizes))
    return resource_exhausted(
        strprintf("texel_density %g gives a chart over %d texels wide; max_resolution is %d",
                  density, static_cast<int>(kMaxRectSide), max_side));
  // Lower bound: the padded rectangles' total area, and the widest chart.
  double area = 0;
  int widest = 0;
  for (const auto& s : sizes) {
    area += static_cast<double>(s[0] + padding) * static_cast<double>(s[1] + padding);
    widest = std::max({widest, s[0], s[1]});
  }
  int fail = 0;
  int side =
      std::max(round_up_to_4(std::sqrt(area) + padding), round_up_to_4(widest + 2.0 * padding));
  while (shelf_pack(sizes, side, padding).empty()) {
    if (side >= static_cast<int>(kMaxRectSide))
      return resource_exhausted(
          strprintf("texel_density %g needs an atlas over %d texels wide; max_resolution is %d",
                    density, side, max_side));
    fail = side;
    side = round_up_to_4(side * 1.25);
  }
  // Smallest fitting multiple of 4 in (fail, side].
  while (side - fail > 4) {
    const int mid = (fail + side) / 8 * 4;
    if (mid <= fail) break;
    (shelf_pack(sizes, mid, padding).empty() ? fail : side) = mid;
  }
  if (side > max_side)
    return resource_exhausted(
        strprintf("texel_density %g needs a %dx%d lightmap atlas; max_resolution is %d", density,
                  side, side, max_side));
  return make_layout(charts, density, side, padding);
}

}  // namespace luxel::atlas
