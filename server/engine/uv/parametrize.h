// The working form of a chart during parametrization, and the planar fast
// path (charts.h, step 3).
#pragma once

#include <cstdint>
#include <vector>

#include "common/dvec3.h"
#include "scene/scene.h"
#include "uv/topology.h"

namespace luxel::uv {

struct DVec2 {
  double x = 0, y = 0;
};

// A chart being parametrized. Its vertices are topological (welded) vertices:
// mesh vertices split only by a normal or UV seam inside the chart get one
// UV, so the chart has no interior cracks.
struct LocalChart {
  std::vector<uint32_t> triangles;  // mesh triangles
  std::vector<uint32_t> welded;     // topological vertex of each local vertex
  std::vector<DVec3> position;      // per local vertex (of its first mesh vertex)
  std::vector<uint32_t> indices;    // 3 per triangle, into the local vertices
  std::vector<DVec2> uv;            // per local vertex
  DVec3 mean_normal;                // area-weighted, unit
  double cone_half_angle = 0;       // largest angle of a face normal to mean_normal (radians)
  double area_3d = 0;
};

LocalChart make_local_chart(const scene::Mesh& mesh, const Topology& topo,
                            std::vector<uint32_t> triangles);

// Orthographic projection onto the plane through the origin perpendicular to
// mean_normal, with a right-handed frame (t, b, n): a triangle wound
// counter-clockwise about n stays counter-clockwise in UV. Exact (an isometry)
// for a planar chart.
void project_planar(LocalChart& chart);

}  // namespace luxel::uv
