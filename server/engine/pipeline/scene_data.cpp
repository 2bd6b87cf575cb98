#include "pipeline/scene_data.h"

#include <cstring>

namespace luxel::pipeline {
namespace {

cl::float4 f4(Vec3 v, float w = 0) {
  return {v.x, v.y, v.z, w};
}
float int_bits(int32_t i) {
  float f;
  std::memcpy(&f, &i, sizeof f);
  return f;
}

// A material that is a rough dielectric everywhere needs no GGX layer for
// irradiance (DESIGN.md: leave out what the scene does not need). Only at the
// default ior: the coating this leaves out (docs/accuracy.md) is 4 % there,
// and grows with the ior, so another ior keeps its GGX layer.
bool is_rough_dielectric(const scene::Material& m) {
  return m.metallic_factor <= 0.0f && m.roughness_factor >= 1.0f &&
         m.metallic_roughness_texture.texture < 0 && m.ior == 1.5f;
}

cl::LuxMaterial to_device(const scene::Material& m) {
  cl::LuxMaterial d{};
  d.base_color = {m.base_color_factor.x, m.base_color_factor.y, m.base_color_factor.z,
                  m.base_color_factor.w};
  const float s = m.emissive_strength;
  d.emission = {m.emissive_factor.x * s, m.emissive_factor.y * s, m.emissive_factor.z * s, 0};
  d.metallic = m.metallic_factor;
  d.roughness = m.roughness_factor;
  // Only TEXCOORD_0 is carried per triangle; a texture on another set is
  // left out (named in the import warnings).
  d.base_color_tex = m.base_color_texture.texcoord == 0 ? m.base_color_texture.texture : -1;
  d.metallic_roughness_tex =
      m.metallic_roughness_texture.texcoord == 0 ? m.metallic_roughness_texture.texture : -1;
  d.emissive_tex = m.emissive_texture.texcoord == 0 ? m.emissive_texture.texture : -1;
  d.flags = (m.double_sided ? LUX_MATERIAL_DOUBLE_SIDED : 0) |
            (m.is_emissive() ? LUX_MATERIAL_EMISSIVE : 0);
  d.alpha_cutoff = m.alpha_cutoff;
  d.dielectric_f0 = m.dielectric_f0();
  return d;
}

}  // namespace

Result<SceneData> prepare_scene_data(const scene::Scene& scene, const accel::TriangleSoup& soup,
                                     const atlas::Atlas& atlas,
                                     const std::vector<int32_t>& triangle_light) {
  SceneData out;
  const size_t n = soup.size();
  if (triangle_light.size() != n)
    return internal_error(
        strprintf("light table covers %zu triangles, the scene has %zu", triangle_light.size(), n));
  out.materials.reserve(scene.materials.size());
  for (const auto& m : scene.materials) out.materials.push_back(to_device(m));

  out.instance_first.assign(scene.instances.size(), 0);
  uint32_t first = 0;
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    out.instance_first[i] = first;
    first += static_cast<uint32_t>(
        scene.meshes[static_cast<size_t>(scene.instances[i].mesh)].triangle_count());
  }
  if (first != n)
    return internal_error(strprintf("triangle soup has %zu triangles, instances %u", n, first));

  std::vector<bool> material_used(scene.materials.size(), false);
  out.surface.resize(n);
  out.atlas_uvs.resize(n);
  for (size_t t = 0; t < n; ++t) {
    const uint32_t inst = soup.instance[t];
    const auto& instance = scene.instances[inst];
    const auto& mesh = scene.meshes[static_cast<size_t>(instance.mesh)];
    const size_t mt = soup.mesh_triangle[t];
    const int32_t material = mesh.triangle_material[mt];
    material_used[static_cast<size_t>(material)] = true;
    cl::LuxSurfaceTri& s = out.surface[t];
    s.p0 = f4(soup.v(t, 0), int_bits(material));
    s.p1 = f4(soup.v(t, 1), int_bits(triangle_light[t]));
    s.p2 = f4(soup.v(t, 2), int_bits(static_cast<int32_t>(inst)));
    cl::float4* normals[3] = {&s.n0, &s.n1, &s.n2};
    cl::float2* uvs[3] = {&s.uv0, &s.uv1, &s.uv2};
    cl::float2* atlas_uv[3] = {&out.atlas_uvs[t].uv0, &out.atlas_uvs[t].uv1, &out.atlas_uvs[t].uv2};
    for (int k = 0; k < 3; ++k) {
      const uint32_t vi = mesh.indices[mt * 3 + static_cast<size_t>(k)];
      Vec3 nw = normalize(transform_normal(instance.object_to_world, mesh.normals[vi]));
      if (!is_finite(nw)) nw = {0, 1, 0};
      *normals[k] = f4(nw);
      const Vec2 uv = mesh.uv0.empty() ? Vec2{0, 0} : mesh.uv0[vi];
      *uvs[k] = {uv.x, uv.y};
      const Vec2 a = atlas.to_atlas(inst, mesh.uv1[vi]);
      *atlas_uv[k] = {a.x, a.y};
    }
    out.atlas_uvs[t].pad = {0, 0};
    s.pad = {0, 0};
  }
  for (size_t m = 0; m < scene.materials.size(); ++m) {
    if (!material_used[m]) continue;
    const auto& mat = scene.materials[m];
    const auto& d = out.materials[m];
    if (d.base_color_tex >= 0 || d.metallic_roughness_tex >= 0) out.uses_textures = true;
    if (mat.is_emissive() && d.emissive_tex >= 0) out.uses_emissive_texture = true;
    if (!is_rough_dielectric(mat)) out.needs_specular = true;
  }
  return out;
}

}  // namespace luxel::pipeline
