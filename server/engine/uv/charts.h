// Chart segmentation and parametrization: the first stage of lightmap UV
// generation (chart.h describes the stages and the Chart record).
//
//   1. Topology (topology.h): vertices are welded by position, so meshes that
//      glTF split at normal or UV seams are connected again; an edge joins two
//      triangles only if they have the same material, a dihedral angle below
//      the limit, consistent winding and, where the file duplicated the
//      vertices, matching vertex normals (a hard edge in the file is a cut).
//   2. Segmentation (segment.h): region growing from the largest unassigned
//      triangle, bounded by a normal cone and a triangle count.
//   3. Parametrization: planar projection for charts whose normal cone is
//      (almost) flat, LSCM (lscm.h; Lévy et al. 2002) otherwise.
//   4. Validation (validate.h): no flipped or zero-area UV triangle, no
//      crossing boundary edges; a rejected chart is split in two along the
//      principal axis of its triangle centroids and each part is retried. A
//      long thin chart (bounding-rectangle aspect over the limit) or one whose
//      L2 stretch is over the limit is split the same way. A single triangle
//      is always valid.
//   5. Layout (chart_layout.h): scale to UV area == 3D area, rotate to the
//      minimum-area bounding rectangle (long side along u), bbox min at (0,0).
//
// Degenerate input: a triangle that references a non-finite position or a
// vertex out of range is an INVALID_ARGUMENT naming the mesh and triangle (it
// is corrupt data, not geometry to skip); a zero-area triangle (repeated
// vertex, collinear corners) is skipped: it is in no chart and is counted.
//
// Deterministic: the same mesh and options give bit-identical charts (no hash
// iteration order or threads decide anything).
#pragma once

#include <cstddef>
#include <vector>

#include "common/status.h"
#include "scene/scene.h"
#include "uv/chart.h"

namespace luxel::uv {

struct ChartOptions {
  // Maximum half-angle of the cone bounding a chart's face normals (degrees).
  double max_cone_half_angle_deg = 50.0;
  // Two triangles are never joined across an edge sharper than this (degrees
  // between face normals).
  double max_dihedral_deg = 60.0;
  // Charts whose normal cone half-angle is at most this are projected onto
  // their average-normal plane instead of solving LSCM (degrees).
  double planar_cone_half_angle_deg = 1.0;
  // Where the file duplicated an edge's vertices, the vertex normals on both
  // sides must agree within this angle for the edge to be crossed (degrees).
  double hard_edge_normal_deg = 1.0;
  // Vertices closer than this fraction of the mesh's bounding-box diagonal are
  // the same topological vertex.
  double weld_relative_epsilon = 1e-6;
  // Weight of the compactness term (growth of perimeter^2 / area) against the
  // normal-deviation term in the region-growing priority.
  double compactness_weight = 0.5;
  // Chart size cap: keeps each LSCM solve small (the solve is superlinear).
  size_t max_chart_triangles = 4096;
  // Charts of more than two triangles whose minimum bounding rectangle is
  // longer than this ratio are split.
  double max_aspect = 16.0;
  // Charts whose L2 stretch (Sander et al. 2001; stretch.h) exceeds this are
  // split; LSCM keeps angles, so this bounds its area distortion. 0: no limit.
  double max_stretch_l2 = 1.2;
  // Rotate each chart to its minimum-area bounding rectangle.
  bool rotate_to_min_rect = true;
};

struct ChartStats {
  size_t triangles = 0;             // triangles in the mesh
  size_t degenerate_triangles = 0;  // zero-area: in no chart
  size_t charts = 0;                // charts returned
  size_t planar_charts = 0;         // parametrized by projection
  size_t lscm_charts = 0;           // parametrized by LSCM
  size_t rejected_splits = 0;       // charts split because validation failed
  size_t aspect_splits = 0;         // charts split because they were long and thin
  size_t stretch_splits = 0;        // charts split because their L2 stretch was too high
  size_t welded_vertices = 0;       // topological vertices after welding
};

// Segments and parametrizes one mesh. Every non-degenerate triangle is in
// exactly one chart. Errors: INVALID_ARGUMENT naming the mesh (and triangle)
// for malformed input or options.
Result<std::vector<Chart>> build_charts(const scene::Mesh& mesh, const ChartOptions& options = {},
                                        ChartStats* stats = nullptr);

}  // namespace luxel::uv
