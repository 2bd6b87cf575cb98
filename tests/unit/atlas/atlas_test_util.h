// Helpers for the atlas tests: synthetic scenes built as scene::Scene structs
// and an independent brute-force point-in-triangle test.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "atlas/atlas.h"
#include "atlas/sample_info.h"
#include "scene/scene.h"

namespace luxel::atlas::testing {

// A scene with one mesh per add_mesh call and one instance per instance call.
struct SceneBuilder {
  scene::Scene scene;
  SceneBuilder() { scene.materials.push_back(scene::Material{}); }
  // Positions default to the UVs on z = 0 (world area = UV area).
  int add_mesh(std::vector<Vec2> uv1, std::vector<uint32_t> indices,
               std::vector<Vec3> positions = {});
  void instance(int mesh, Mat4 object_to_world = {});
};

Mat4 scale_translate(double sx, double sy, double sz, double tx = 0, double ty = 0, double tz = 0);

// Two triangles covering [u0,u1] x [v0,v1] (diagonal (u0,v0)-(u1,v1)).
int add_quad(SceneBuilder& b, float u0, float v0, float u1, float v1);

// Signed distance-like margin of (x, y) inside the triangle: the minimum over
// the edges of the signed distance to the edge line (positive inside),
// computed independently of the rasteriser.
double inside_margin(const TexelTriangle& t, double x, double y);

// Every world triangle of the scene in texel space, in (instance, triangle) order.
struct WorldTriangle {
  uint32_t instance, triangle;
  TexelTriangle texel;
};
std::vector<WorldTriangle> world_triangles(const scene::Scene& scene, const Atlas& atlas);

Atlas expect_atlas(const scene::Scene& scene, const AtlasSettings& settings);
SampleInfo expect_sample_info(const scene::Scene& scene, const Atlas& atlas);

// Packed rectangles lie inside the atlas, `padding` texels from its border and
// from each other (gtest expectations).
void expect_disjoint_padded(const Atlas& atlas, int padding);

// Records of the covered_index-th covered texel (texels are stored in
// ascending order, so its words end where the next texel's begin).
size_t record_count(const SampleInfo& info, size_t covered_index);

}  // namespace luxel::atlas::testing
