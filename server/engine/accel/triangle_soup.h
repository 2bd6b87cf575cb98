// World-space triangles of a scene: every instance's mesh transformed to
// world space (instancing is flattened for traversal; the scene model keeps
// meshes shared). Index i here is the "original triangle id" reported by both
// tracers in LuxHit::prim.
#pragma once

#include <cstdint>
#include <vector>

#include "common/math.h"
#include "common/status.h"
#include "kernels/shared/geometry.h"
#include "scene/scene.h"

namespace luxel::accel {

struct TriangleSoup {
  std::vector<Vec3> vertices;           // 3 per triangle, world space
  std::vector<uint32_t> instance;       // per triangle: index into Scene::instances
  std::vector<uint32_t> mesh_triangle;  // per triangle: triangle index within its mesh
  std::vector<int32_t> alpha_mask;      // per triangle: -1 opaque, else index into masks
  std::vector<cl::LuxTriangleUV> uvs;   // per triangle material UVs (only when masks exist)
  std::vector<cl::LuxAlphaMask> masks;  // one per alpha-masked material
  std::vector<uint8_t> alpha_texels;    // 8-bit alpha of every mask, concatenated
  Bounds3 bounds;

  size_t size() const { return instance.size(); }
  bool has_alpha_masks() const { return !masks.empty(); }
  Vec3 v(size_t tri, int k) const { return vertices[tri * 3 + static_cast<size_t>(k)]; }
};

// Flattens the scene. Fails (naming the instance) if a transform sends a
// vertex to a non-finite position.
Result<TriangleSoup> build_triangle_soup(const scene::Scene& scene);

}  // namespace luxel::accel
