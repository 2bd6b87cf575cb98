// Scenes with closed-form irradiance, built in memory for the bake tests.
#pragma once

#include <cmath>
#include <string>

#include "common/math.h"
#include "scene/scene.h"

namespace luxel::testing {

// Adds a quad (two triangles) as its own mesh + instance. Corners o, o+eu,
// o+eu+ev, o+ev; the front side (normal) is cross(eu, ev). uv1 maps the
// corners to the lightmap rectangle [u0,u1] x [v0,v1] (u along eu, v along ev).
inline void add_quad(scene::Scene& s, Vec3 o, Vec3 eu, Vec3 ev, float u0, float v0, float u1,
                     float v1, int material) {
  scene::Mesh m;
  m.name = "quad" + std::to_string(s.meshes.size());
  m.positions = {o, o + eu, o + eu + ev, o + ev};
  const Vec3 n = normalize(cross(eu, ev));
  m.normals = {n, n, n, n};
  m.uv0 = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  m.uv1 = {{u0, v0}, {u1, v0}, {u1, v1}, {u0, v1}};
  m.indices = {0, 1, 2, 0, 2, 3};
  m.triangle_material = {material, material};
  s.meshes.push_back(m);
  scene::Instance inst;
  inst.name = m.name;
  inst.mesh = static_cast<int>(s.meshes.size() - 1);
  s.instances.push_back(inst);
}

inline scene::Material diffuse_material(float albedo, float emission = 0) {
  scene::Material m;
  m.name = "diffuse";
  m.base_color_factor = {albedo, albedo, albedo, 1};
  m.metallic_factor = 0;
  m.roughness_factor = 1;
  m.emissive_factor = {emission, emission, emission};
  return m;
}

// A 2 x 2 plane at y = 0 facing +y; its lightmap covers the whole atlas:
// atlas (u, v) -> world (x, z) = (-1 + 2 v, -1 + 2 u).
inline scene::Scene open_plane(float albedo = 0.5f) {
  scene::Scene s;
  s.source_name = "open_plane";
  s.materials.push_back(diffuse_material(albedo));
  add_quad(s, {-1, 0, -1}, {0, 0, 2}, {2, 0, 0}, 0, 0, 1, 1, 0);
  return s;
}

// Closed cube [-scale,scale]^3 with inward-facing walls of albedo a, each
// emitting radiance le (irradiance inside does not depend on the scale). Faces in a 3 x 2 grid of
// the atlas with a margin.
inline scene::Scene furnace_box(float albedo, float le, float scale = 1.0f) {
  scene::Scene s;
  s.source_name = "furnace_box";
  s.materials.push_back(diffuse_material(albedo, le));
  const Vec3 normals[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  const float margin = 0.02f;
  for (int f = 0; f < 6; ++f) {
    const Vec3 n = normals[f];  // inward normal: the wall at -n
    const Vec3 axis = std::fabs(n.y) > 0.5f ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    const Vec3 eu = normalize(cross(n, axis)) * (2.0f * scale);
    const Vec3 ev = normalize(cross(n, eu)) * (2.0f * scale);  // cross(eu, ev) along n
    const Vec3 o = n * -scale - eu * 0.5f - ev * 0.5f;
    const float cu = static_cast<float>(f % 3) / 3.0f, cv = static_cast<float>(f / 3) / 2.0f;
    add_quad(s, o, eu, ev, cu + margin, cv + margin, cu + 1.0f / 3.0f - margin, cv + 0.5f - margin,
             0);
  }
  return s;
}

}  // namespace luxel::testing
