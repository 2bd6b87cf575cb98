#include "atlas_test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace luxel::atlas::testing {

int SceneBuilder::add_mesh(std::vector<Vec2> uv1, std::vector<uint32_t> indices,
                           std::vector<Vec3> positions) {
  scene::Mesh m;
  m.name = "mesh" + std::to_string(scene.meshes.size());
  if (positions.empty())
    for (const Vec2& uv : uv1) positions.push_back({uv.x, uv.y, 0});
  m.positions = std::move(positions);
  m.normals.assign(m.positions.size(), Vec3{0, 0, 1});
  m.uv0 = uv1;
  m.uv1 = std::move(uv1);
  m.indices = std::move(indices);
  m.triangle_material.assign(m.indices.size() / 3, 0);
  scene.meshes.push_back(std::move(m));
  return static_cast<int>(scene.meshes.size()) - 1;
}

void SceneBuilder::instance(int mesh, Mat4 object_to_world) {
  scene::Instance i;
  i.name = "node" + std::to_string(scene.instances.size());
  i.node_index = static_cast<int>(scene.instances.size());
  i.mesh = mesh;
  i.object_to_world = object_to_world;
  scene.instances.push_back(i);
}

Mat4 scale_translate(double sx, double sy, double sz, double tx, double ty, double tz) {
  Mat4 m;
  m.at(0, 0) = sx;
  m.at(1, 1) = sy;
  m.at(2, 2) = sz;
  m.at(0, 3) = tx;
  m.at(1, 3) = ty;
  m.at(2, 3) = tz;
  return m;
}

int add_quad(SceneBuilder& b, float u0, float v0, float u1, float v1) {
  return b.add_mesh({{u0, v0}, {u1, v0}, {u1, v1}, {u0, v1}}, {0, 1, 2, 0, 2, 3});
}

double inside_margin(const TexelTriangle& t, double x, double y) {
  const double area2 =
      (t.x[1] - t.x[0]) * (t.y[2] - t.y[0]) - (t.y[1] - t.y[0]) * (t.x[2] - t.x[0]);
  double margin = INFINITY;
  for (int k = 0; k < 3; ++k) {
    const int n = (k + 1) % 3;
    const double ex = t.x[n] - t.x[k], ey = t.y[n] - t.y[k];
    const double len = std::hypot(ex, ey);
    const double side = (ex * (y - t.y[k]) - ey * (x - t.x[k])) / len;
    margin = std::min(margin, area2 >= 0 ? side : -side);
  }
  return margin;
}

std::vector<WorldTriangle> world_triangles(const scene::Scene& scene, const Atlas& atlas) {
  std::vector<WorldTriangle> out;
  for (uint32_t i = 0; i < scene.instances.size(); ++i) {
    const auto& mesh = scene.meshes[static_cast<size_t>(scene.instances[i].mesh)];
    for (uint32_t t = 0; t < mesh.triangle_count(); ++t)
      out.push_back({i, t, texel_triangle(scene, atlas, i, t)});
  }
  return out;
}

Atlas expect_atlas(const scene::Scene& scene, const AtlasSettings& settings) {
  auto atlas = build_atlas(scene, settings);
  EXPECT_TRUE(atlas.is_ok()) << atlas.status().to_string();
  return atlas.is_ok() ? atlas.value() : Atlas{};
}

SampleInfo expect_sample_info(const scene::Scene& scene, const Atlas& atlas) {
  auto info = build_sample_info(scene, atlas);
  EXPECT_TRUE(info.is_ok()) << info.status().to_string();
  return info.is_ok() ? std::move(info.value()) : SampleInfo{};
}

void expect_disjoint_padded(const Atlas& atlas, int padding) {
  for (size_t i = 0; i < atlas.placements.size(); ++i) {
    const int* r = atlas.placements[i].rect;
    EXPECT_GE(r[0], padding);
    EXPECT_GE(r[1], padding);
    EXPECT_LE(r[0] + r[2] + padding, atlas.width);
    EXPECT_LE(r[1] + r[3] + padding, atlas.height);
    for (size_t j = 0; j < i; ++j) {
      const int* q = atlas.placements[j].rect;
      const bool apart = r[0] + r[2] + padding <= q[0] || q[0] + q[2] + padding <= r[0] ||
                         r[1] + r[3] + padding <= q[1] || q[1] + q[3] + padding <= r[1];
      EXPECT_TRUE(apart) << "rectangles " << i << " and " << j;
    }
  }
}

size_t record_count(const SampleInfo& info, size_t covered_index) {
  const uint32_t begin = info.offsets[info.covered_texels[covered_index]];
  const size_t end = covered_index + 1 < info.covered_texels.size()
                         ? info.offsets[info.covered_texels[covered_index + 1]]
                         : info.words.size();
  return (end - begin - 2) / 4;
}

}  // namespace luxel::atlas::testing
