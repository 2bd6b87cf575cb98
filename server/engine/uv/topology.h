// Mesh topology for chart segmentation: welded vertices, per-triangle
// geometry and which edges a chart may cross (charts.h, step 1).
#pragma once

#include <cstdint>
#include <vector>

#include "common/dvec3.h"
#include "common/status.h"
#include "scene/scene.h"
#include "uv/charts.h"

namespace luxel::uv {

struct Topology {
  std::vector<uint32_t> weld;  // mesh vertex -> topological vertex (dense ids)
  size_t welded_count = 0;
  std::vector<uint8_t> valid;  // per triangle: non-degenerate (else in no chart)
  size_t degenerate_count = 0;
  std::vector<DVec3> normal;        // per triangle, unit (zero when degenerate)
  std::vector<DVec3> centroid;      // per triangle
  std::vector<double> area;         // per triangle (object space)
  std::vector<double> edge_length;  // 3 per triangle: |v[(i+1)%3] - v[i]|
  // 3 per triangle: the triangle across edge (v[i], v[(i+1)%3]) when a chart
  // may cross that edge, else -1 (border, cut, non-manifold).
  std::vector<int32_t> neighbour;
};

// Zero-area test shared by topology and validation: twice the area is at most
// this fraction of the longest edge squared (about the sine of the smallest
// angle), below what float corner positions resolve.
inline constexpr double kDegenerateSine = 1e-7;

// INVALID_ARGUMENT naming the mesh and triangle for indices out of range or
// non-finite positions.
Result<Topology> build_topology(const scene::Mesh& mesh, const ChartOptions& options);

}  // namespace luxel::uv
