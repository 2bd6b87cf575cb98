// Scene statistics printed by `luxel inspect` (and later returned by the
// service on upload).
#pragma once

#include <string>
#include <vector>

#include "scene/scene.h"

namespace luxel::scene {

struct SceneStats {
  size_t meshes = 0;
  size_t instances = 0;
  size_t mesh_triangles = 0;   // unique triangles (each mesh once)
  size_t world_triangles = 0;  // after instancing
  size_t materials = 0;
  size_t textures = 0;
  size_t texture_bytes = 0;           // host memory of decoded textures
  size_t alpha_masked_triangles = 0;  // world triangles with alphaMode MASK
  size_t point_lights = 0, spot_lights = 0, directional_lights = 0;
  size_t emissive_triangles = 0;  // world triangles with an emissive material
  // Total emitted power of the emissive triangles, in glTF emissive units x m^2
  // (sum over triangles of area * pi * mean(emissive factor * strength); the
  // emissive texture's mean is used when there is one).
  double emissive_power = 0.0;
  Bounds3 world_bounds;
  // Lightmap UV (TEXCOORD_1) coverage, rasterized at coverage_resolution^2
  // with every mesh in the same unit square: fraction of texels whose centre
  // is inside at least one UV triangle; texels covered twice by one mesh (a
  // UV error: two surfaces would share lightmap texels); texels covered by
  // several meshes (normal for instanced meshes and per-mesh layouts, which
  // get their own atlas rectangles when packed; an error in a single-atlas
  // scene such as the shared benchmark scenes).
  int coverage_resolution = 512;
  double lightmap_coverage = 0.0;
  size_t lightmap_overlap_texels = 0;
  size_t lightmap_shared_texels = 0;
  size_t degenerate_triangles_dropped = 0;
  size_t skipped_primitives = 0;
};

SceneStats compute_stats(const Scene& scene, int coverage_resolution = 512);

// A mesh whose lightmap UVs (TEXCOORD_1) overlap themselves: `texels` texel
// centres of a resolution^2 grid over the unit square lie inside two or more
// of its UV triangles. Every instance of the mesh then has two surfaces
// sharing lightmap texels (instances get their own atlas rectangles, so
// overlap between meshes or instances is not counted). A centre on an edge
// shared by two triangles counts once.
struct UvOverlap {
  int mesh = -1;  // index into Scene::meshes
  size_t texels = 0;
};

// The meshes with overlapping TEXCOORD_1, in mesh order; linear in the
// triangle count (each triangle costs the rows it spans).
std::vector<UvOverlap> find_uv_overlaps(const Scene& scene, int resolution = 512);

// Multi-line human-readable report.
std::string format_stats(const SceneStats& stats);

}  // namespace luxel::scene
