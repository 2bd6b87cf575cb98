// Internal to uv/generate.cpp and uv/generate_assembly.cpp: the charts of
// each mesh, what was handed to the packer and where it put them.
#pragma once

#include <cstdint>
#include <vector>

#include "uv/bitimage_packer.h"
#include "uv/charts.h"
#include "uv/generate.h"

namespace luxel::uv {

struct DPoint {
  double x = 0, y = 0;
};

// Where the packer puts a shape point (bitimage_packer.h:
// atlas_texel(p) = rotate(p, rotation) + offset), in double.
DPoint placed_point(double x, double y, const ShapePlacement& s);

// One baked mesh: its charts and the instances that use it.
struct MeshCharts {
  std::vector<Chart> charts;
  std::vector<uint32_t> instances;
  // Per chart: world texels per chart UV unit at density 1 (sqrt of world
  // area over chart area) for a mesh used once; for an instanced mesh, per
  // instance (the mesh's mean).
  std::vector<double> chart_scale;
  std::vector<double> instance_scale;
  // The instance scale the mesh's own layout is packed at: the smallest
  // instance's, raised to a kMaxGrow-th of the largest's. Each instance is
  // the layout grown by grow(k) >= 1, so padding never shrinks below
  // padding_texels; the layout's fixed costs (padding, whole texels per
  // chart) grow with it, and bounding the growth bounds that waste. Smaller
  // instances than layout_scale get more texels per unit than asked for
  // (UvReport::density_spread says how much).
  double layout_scale = 0;
  static constexpr double kMaxGrow = 4;
  double grow(size_t k) const { return std::max(instance_scale[k], layout_scale) / layout_scale; }
};

// A shape handed to the packer: a chart of a mesh used once, or one
// instance of an instanced mesh's own layout.
struct ShapeSource {
  uint32_t mesh = 0;
  uint32_t chart = 0;     // chart of a mesh used once
  int32_t instance = -1;  // instance of an instanced mesh (-1: a chart)
};

// An instanced mesh's own layout, packed once per density.
struct MeshLayout {
  int width = 0, height = 0;
  std::vector<ShapePlacement> placements;  // per chart
  double scale = 0;                        // texels per chart UV unit in the layout
};

struct PackAttempt {
  PackResult pack;  // one page: placements in page texels; multi-page: the pages' concatenated
  std::vector<ShapeSource> sources;
  std::vector<MeshLayout> layouts;  // per mesh (instanced ones only)
  std::vector<int> page;            // per shape (all 0 on one page)
  int pages = 1;
};

// Step 3 of generate_lightmap_uvs: UVs, split vertices and placements into
// `out` (out.scene starts as `scene`) for `attempt` packed at `density`.
void assemble_atlas(const scene::Scene& scene, const std::vector<MeshCharts>& meshes,
                    const PackAttempt& attempt, double density, GeneratedUvs& out);

}  // namespace luxel::uv
