// Packed atlas layout: one rectangle per instance, at one texel density for
// the whole scene, shelf-packed into a square.
//
// A chart is an instance's TEXCOORD_1 bounding box. At density d (texels per
// world unit) it is scaled by d * sqrt(world area / UV area) texels per UV
// unit, so that its texel count matches its world area like every other
// chart's. The chart starts kChartInsetTexels inside its rectangle, which is
// floor(extent * scale + 2 * inset) + 1 texels on each side: the half-open
// texels [x, x + w) then hold every point of the chart with a margin that
// absorbs float rounding of the UVs, scale and offset, so a chart never
// reaches into the padding.
#pragma once

#include <array>
#include <vector>

#include "common/status.h"

namespace luxel::atlas {

// Where a chart starts within its rectangle, in texels (float atlas UVs are
// good to ~1e-3 texel at 8192^2).
constexpr double kChartInsetTexels = 1.0 / 64;

struct ChartExtent {
  double uv_width = 0, uv_height = 0;  // UV bounding box
  // Texels per UV unit per unit density: sqrt(world area / UV area). 0 for an
  // instance with no world area, which gets one texel whatever the density.
  double stretch = 0;
};

struct PackedLayout {
  int side = 0;                           // square atlas side in texels
  double density = 0;                     // texels per world unit
  std::vector<double> texels_per_uv;      // per chart: scale applied to its UVs
  std::vector<std::array<int, 4>> rects;  // per chart: x, y, w, h in texels
};

// Places rectangles (w, h) on shelves, tallest first, `padding` texels apart
// and from the border. Returns the positions (x, y) in input order, or an
// empty vector when they do not fit in side x side.
std::vector<std::array<int, 2>> shelf_pack(const std::vector<std::array<int, 2>>& sizes, int side,
                                           int padding);

// The largest density whose charts fit a side x side atlas (binary search).
// RESOURCE_EXHAUSTED when the charts do not fit even at one texel each.
Result<PackedLayout> pack_at_resolution(const std::vector<ChartExtent>& charts, int side,
                                        int padding);

// The smallest square side (a multiple of 4) that holds the charts at
// `density`. RESOURCE_EXHAUSTED naming the needed side when it exceeds
// max_side.
Result<PackedLayout> pack_at_density(const std::vector<ChartExtent>& charts, double density,
                                     int padding, int max_side);

}  // namespace luxel::atlas
