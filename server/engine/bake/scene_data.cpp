#include "bake/scene_data.h"

#include <cmath>
#include <cstring>

#include "scene/tangents.h"

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
// A dielectric with specularFactor 0 (KHR_materials_specular; how the importer
// bakes KHR_materials_unlit) has F0 = F90 = 0: no specular layer at any
// roughness or ior, and its diffuse weight 1 - F is exactly 1, so leaving the
// layer out changes nothing.
bool is_rough_dielectric(const scene::Material& m) {
  if (m.metallic_factor <= 0.0f && m.metallic_roughness_texture.texture < 0 &&
      m.specular_factor == 0.0f)
    return true;
  return m.metallic_factor <= 0.0f && m.roughness_factor >= 1.0f &&
         m.metallic_roughness_texture.texture < 0 && m.ior == 1.5f && m.specular_factor == 1.0f &&
         m.specular_color_factor.x == 1.0f && m.specular_color_factor.y == 1.0f &&
         m.specular_color_factor.z == 1.0f;
}

int wrap_code(scene::WrapMode w) {
  switch (w) {
    case scene::WrapMode::kClampToEdge:
      return LUX_WRAP_CLAMP;
    case scene::WrapMode::kMirroredRepeat:
      return LUX_WRAP_MIRROR;
    case scene::WrapMode::kRepeat:
      break;
  }
  return LUX_WRAP_REPEAT;
}

cl::LuxTextureSlot to_slot(const scene::TextureRef& r) {
  cl::LuxTextureSlot s{};
  s.texture = r.texture;
  s.m00 = s.m11 = 1.0f;
  s.flags = (r.texcoord == 1 ? LUX_SLOT_TEXCOORD1 : 0) |
            LUX_SLOT_MAKE_WRAP(wrap_code(r.wrap_s), wrap_code(r.wrap_t));
  if (r.has_transform) {
    const auto m = r.uv_matrix();
    s.m00 = static_cast<float>(m[0]);
    s.m01 = static_cast<float>(m[1]);
    s.m02 = static_cast<float>(m[2]);
    s.m10 = static_cast<float>(m[3]);
    s.m11 = static_cast<float>(m[4]);
    s.m12 = static_cast<float>(m[5]);
    s.flags |= LUX_SLOT_TRANSFORM;
  }
  return s;
}

cl::LuxMaterial to_device(const scene::Material& m) {
  cl::LuxMaterial d{};
  d.base_color = {m.base_color_factor.x, m.base_color_factor.y, m.base_color_factor.z,
                  m.base_color_factor.w};
  const float s = m.emissive_strength;
  d.emission = {m.emissive_factor.x * s, m.emissive_factor.y * s, m.emissive_factor.z * s, 0};
  const Vec3 f0 = m.dielectric_specular_f0();
  d.specular = {f0.x, f0.y, f0.z, m.dielectric_specular_f90()};
  d.metallic = m.metallic_factor;
  d.roughness = m.roughness_factor;
  d.base_color_tex = to_slot(m.base_color_texture);
  d.metallic_roughness_tex = to_slot(m.metallic_roughness_texture);
  d.emissive_tex = to_slot(m.emissive_texture);
  d.normal_tex = to_slot(m.normal_texture);
  d.normal_scale = m.normal_scale;
  d.flags = (m.double_sided ? LUX_MATERIAL_DOUBLE_SIDED : 0) |
            (m.is_emissive() ? LUX_MATERIAL_EMISSIVE : 0);
  d.alpha_cutoff = m.alpha_cutoff;
  return d;
}

// The mesh's tangents: the importer's (TANGENT or generated), or, for meshes
// built without them (scenes made in code, or UVs of another set), generated
// here once per mesh from the UV set the normal map reads.
const std::vector<Vec4>& mesh_tangents(const scene::Scene& scene, int mesh_index, int texcoord,
                                       std::vector<std::vector<Vec4>>* generated) {
  const scene::Mesh& mesh = scene.meshes[static_cast<size_t>(mesh_index)];
  if (mesh.tangents.size() == mesh.positions.size()) return mesh.tangents;
  std::vector<Vec4>& g = (*generated)[static_cast<size_t>(mesh_index)];
  if (g.empty()) {
    std::vector<Vec2> uvs = mesh.material_uvs(texcoord);
    uvs.resize(mesh.positions.size(), Vec2{0, 0});
    g = scene::generate_tangents(mesh.positions, mesh.normals, uvs, mesh.indices);
  }
  return g;
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

  // Material UV set 1 per triangle only when some material reads it: the
  // surface records stay 128 bytes and scenes on TEXCOORD_0 pay nothing.
  bool any_normal_map = false;
  for (const auto& m : scene.materials) {
    for (const scene::TextureRef* r : {&m.base_color_texture, &m.metallic_roughness_texture,
                                       &m.emissive_texture, &m.normal_texture})
      if (r->texture >= 0 && r->texcoord == 1) out.uses_texcoord1 = true;
    if (m.normal_texture.texture >= 0) any_normal_map = true;
  }
  if (out.uses_texcoord1) out.material_uv1.assign(n, cl::LuxTriangleUV{});
  // Tangents likewise only with a normal map (48 bytes per triangle).
  if (any_normal_map) out.tangents.assign(n, cl::LuxTriangleTangents{});
  std::vector<std::vector<Vec4>> generated(scene.meshes.size());

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
      if (!out.material_uv1.empty()) {
        const Vec2 u1 = mesh.material_uvs(1).empty() ? Vec2{0, 0} : mesh.material_uvs(1)[vi];
        (&out.material_uv1[t].uv0)[k] = {u1.x, u1.y};
      }
      // The probe domain has no lightmap (no placements, maybe no UV set 1).
      const Vec2 a = atlas.placements.empty() || mesh.uv1.empty()
                         ? Vec2{0, 0}
                         : atlas.to_atlas(inst, mesh.uv1[vi]);
      *atlas_uv[k] = {a.x, a.y};
    }
    out.atlas_uvs[t].pad = {0, 0};
    // The triangle keeps the file's vertex order; under a mirroring instance
    // its front face is the clockwise one (LuxSurfaceTri.front).
    s.front = front_face_sign(instance.object_to_world);
    s.pad = 0;
    const auto& normal_map = scene.materials[static_cast<size_t>(material)].normal_texture;
    if (!out.tangents.empty() && normal_map.texture >= 0) {
      const std::vector<Vec4>& tangents =
          mesh_tangents(scene, instance.mesh, normal_map.texcoord, &generated);
      // A mirroring transform flips the frame's handedness (bitangent sign):
      // cross(M n, M t) = det(M) M^-T cross(n, t) for the transformed normal.
      const float sign = front_face_sign(instance.object_to_world);
      cl::float4* tw[3] = {&out.tangents[t].t0, &out.tangents[t].t1, &out.tangents[t].t2};
      for (int k = 0; k < 3; ++k) {
        const Vec4 to = tangents[mesh.indices[mt * 3 + static_cast<size_t>(k)]];
        Vec3 w = transform_vector(instance.object_to_world, {to.x, to.y, to.z});
        const float len = length(w);
        w = len > 0 && std::isfinite(len) ? w * (1.0f / len) : Vec3{0, 0, 0};
        *tw[k] = f4(w, to.w < 0 ? -sign : sign);
      }
    }
  }
  for (size_t m = 0; m < scene.materials.size(); ++m) {
    if (!material_used[m]) continue;
    const auto& mat = scene.materials[m];
    const auto& d = out.materials[m];
    if (d.base_color_tex.texture >= 0 || d.metallic_roughness_tex.texture >= 0)
      out.uses_textures = true;
    if (mat.is_emissive() && d.emissive_tex.texture >= 0) out.uses_emissive_texture = true;
    if (!is_rough_dielectric(mat)) out.needs_specular = true;
    if (mat.normal_texture.texture >= 0) out.uses_normal_map = true;
  }
  if (!out.uses_normal_map) out.tangents.clear();
  return out;
}

}  // namespace luxel::pipeline
