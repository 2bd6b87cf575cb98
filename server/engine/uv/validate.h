// Chart validation (charts.h, step 4): the properties chart.h promises.
#pragma once

#include <cstdint>
#include <vector>

#include "common/math.h"
#include "uv/chart.h"

namespace luxel::uv {

enum class ChartDefect {
  kNone,
  kNonFinite,         // a UV coordinate is NaN or infinite
  kZeroArea,          // a UV triangle with (almost) no area
  kFlipped,           // a UV triangle wound clockwise
  kBoundaryCrossing,  // two boundary edges of the chart cross (it overlaps itself)
};

const char* chart_defect_name(ChartDefect defect);

// Checks UV triangles over shared vertices (3 indices per triangle): every
// triangle counter-clockwise (the orientation of its 3D winding, see lscm.h
// and parametrize.h) with a sine of its smallest angle above 1e-9 (the
// zero-area test), and no two boundary edges (edges of one triangle only)
// crossing in their interiors. With no flipped triangle and a simple boundary,
// a connected chart does not overlap itself. The crossing test sweeps the
// edges sorted by their lowest u, so it costs O(B log B + pairs whose u
// ranges overlap) for B boundary edges. Orientation is exact for float UVs
// (the 2x2 determinant of float differences evaluated in double).
ChartDefect find_chart_defect(const std::vector<Vec2>& uv, const std::vector<uint32_t>& indices);

// The same check on a finished chart. Chart vertices that share a UV exactly
// are taken as one vertex (mesh vertices on a normal or UV seam inside the
// chart), so the chart's boundary is its true boundary.
ChartDefect validate_chart(const Chart& chart);

}  // namespace luxel::uv
