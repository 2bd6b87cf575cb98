// Chart segmentation (charts.h, step 2) and the splits used when a chart is
// rejected or too long.
#pragma once

#include <cstdint>
#include <vector>

#include "uv/charts.h"
#include "uv/topology.h"

namespace luxel::uv {

// Region growing. Seeds are taken in order of decreasing area (ties: lower
// index). A chart grows across crossable edges (Topology::neighbour) in order
// of a priority that adds the candidate's deviation from the chart's normal
// axis, 1 - cos, to the relative growth of the chart's perimeter^2 / area
// (compactness_weight; it prefers triangles that fill notches and keeps charts
// round). A candidate is refused when the bounding cone of the chart's normals
// would exceed max_cone_half_angle_deg; the cone is merged incrementally (axis
// turned towards the new normal, half-angle the half-sum), so it is a
// conservative bound that costs O(1) per triangle. Returns the charts' mesh
// triangles; degenerate triangles are in none.
std::vector<std::vector<uint32_t>> grow_charts(const Topology& topo, const ChartOptions& options);

// Splits a set of triangles in two halves at the median of their centroids
// along the centroids' principal axis (ties broken by triangle index), then
// into connected parts. Needs at least two triangles.
std::vector<std::vector<uint32_t>> split_chart(const Topology& topo,
                                               const std::vector<uint32_t>& tris);

// Connected parts of a set of triangles through crossable edges, each sorted,
// ordered by their smallest triangle.
std::vector<std::vector<uint32_t>> connected_parts(const Topology& topo,
                                                   std::vector<uint32_t> tris);

}  // namespace luxel::uv
