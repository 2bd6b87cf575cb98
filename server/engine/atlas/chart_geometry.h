// Measurements the atlas is laid out from: each mesh's TEXCOORD_1 layout
// (bounds, area, validity) and each instance's world-space area, plus the
// check whether the layouts of different instances share UV space.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

#include "common/status.h"
#include "scene/scene.h"

namespace luxel::atlas {

struct UvBounds {
  double lo[2] = {INFINITY, INFINITY};
  double hi[2] = {-INFINITY, -INFINITY};
  double width() const { return hi[0] - lo[0]; }
  double height() const { return hi[1] - lo[1]; }
};

struct MeshUvLayout {
  UvBounds bounds;  // over every vertex a triangle references
  double area = 0;  // sum of |UV triangle area| (UV units^2)
  size_t zero_area_triangles = 0;
};

// True when the 2D triangle has no usable area: the sine of its angle at a is
// below 1e-10 (scale-invariant, so the same test holds in UV and texel space).
bool is_zero_area(double ax, double ay, double bx, double by, double cx, double cy);

// Validates a mesh's lightmap UVs (present, one per vertex, finite, not all
// zero-area) and measures them. Errors are INVALID_ARGUMENT naming the mesh.
Result<MeshUvLayout> measure_mesh_uvs(const scene::Mesh& mesh);

// World-space area of the instance (its mesh transformed), in double.
double instance_world_area(const scene::Mesh& mesh, const scene::Instance& instance);

// True when TEXCOORD_1 triangles of two different instances contain the same
// texel centre of a check_resolution^2 grid over [0,1]^2 (UVs outside the
// square are ignored here). Coarse by design: it tells a scene-wide atlas
// (the shared benchmark scenes, whose charts keep a 0.002 margin) from
// per-mesh layouts that all fill the unit square; an overlap smaller than a
// check texel goes unnoticed and only makes a few sample positions contested
// (SampleInfo::contested_samples).
bool instances_share_uv_space(const scene::Scene& scene, int check_resolution);

}  // namespace luxel::atlas
