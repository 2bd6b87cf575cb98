// Final placement of a chart's UVs in its own frame (charts.h, step 5).
#pragma once

#include <vector>

#include "common/math.h"
#include "uv/parametrize.h"

namespace luxel::uv {

struct LaidOutChart {
  std::vector<Vec2> uv;  // per local vertex
  double width = 0;      // bounding rectangle: u extent (>= height when rotated)
  double height = 0;     // v extent
};

// Scales chart.uv so its UV area equals area_3d, optionally rotates it so its
// minimum-area bounding rectangle is axis-aligned (rotating calipers over the
// convex hull: the optimal rectangle has a side on a hull edge; Freeman and
// Shapira 1975), turns it so the long side runs along u, and moves the bounding
// box's minimum to (0, 0). Rotations only, so orientation is kept.
LaidOutChart lay_out_chart(const LocalChart& chart, bool rotate_to_min_rect);

}  // namespace luxel::uv
