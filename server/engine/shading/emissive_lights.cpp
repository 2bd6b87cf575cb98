// Emissive triangles as area lights: one LuxLight per world triangle whose
// material emits (scene::Material::is_emissive).
#include <cmath>
#include <map>

#include "shading/color.h"
#include "shading/light_builders.h"

namespace luxel::pipeline::detail {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Mean luminance of a (linear) texture: the factor by which a textured
// emitter's power differs from its constant radiance. An undecoded texture
// (imported without pixels) counts as 1.
double mean_luminance(const scene::Texture& t) {
  if (!t.has_pixels()) return 1.0;
  const size_t n = t.texel_count();
  double sum = 0;
  for (size_t i = 0; i < n; ++i) {
    const Vec4 l = t.linear(i);
    const Vec3 c{l.x, l.y, l.z};
    if (is_finite(c)) sum += std::max(luminance(c), 0.0);
  }
  return sum / static_cast<double>(n);
}

struct EmitterMaterial {
  Vec3 radiance;
  double power_scale = 0;  // pi x sides x texture mean luminance x luminance(radiance)
  int flags = 0;
};

Result<EmitterMaterial> emitter_material(const scene::Scene& scene, size_t index) {
  const scene::Material& m = scene.materials[index];
  const std::string what = strprintf("material %zu '%s'", index, m.name.c_str());
  LUXEL_RETURN_IF_ERROR(check_color(what, "emissive factor", m.emissive_factor));
  LUXEL_RETURN_IF_ERROR(check_nonnegative(what, "emissive strength", m.emissive_strength));
  EmitterMaterial e;
  e.radiance = m.emissive_factor * m.emissive_strength;
  if (!is_finite(e.radiance))
    return invalid_argument(what + ": emissive factor * strength overflows a float");
  double texture_mean = 1.0;
  const int tex = m.emissive_texture.texture;
  if (tex >= 0) {
    if (tex >= static_cast<int>(scene.textures.size()))
      return invalid_argument(strprintf("%s: emissive texture %d does not exist (%zu textures)",
                                        what.c_str(), tex, scene.textures.size()));
    texture_mean = mean_luminance(scene.textures[static_cast<size_t>(tex)]);
    e.flags |= LUX_LIGHT_FLAG_TEXTURED;
  }
  if (m.double_sided) e.flags |= LUX_LIGHT_FLAG_DOUBLE_SIDED;
  e.power_scale = kPi * (m.double_sided ? 2.0 : 1.0) * texture_mean * luminance(e.radiance);
  return e;
}

}  // namespace

Status add_emissive_triangles(const scene::Scene& scene, const accel::TriangleSoup& soup,
                              std::vector<LightCandidate>* out) {
  std::map<size_t, EmitterMaterial> emitters;  // only emissive materials, validated once
  for (size_t i = 0; i < scene.materials.size(); ++i) {
    if (!scene.materials[i].is_emissive()) continue;
    auto e = emitter_material(scene, i);
    if (!e) return e.status();
    emitters[i] = e.value();
  }
  if (emitters.empty()) return Status::ok();

  // glTF 2.0 §3.7.4: a transform with a negative determinant reverses the
  // winding, so the front face of a mirrored instance's triangle is the
  // other side. The same rule gives the side that BSDF-sampled hits see
  // emit (LuxSurfaceTri.front), so both estimators agree.
  std::vector<float> side(scene.instances.size());
  for (size_t i = 0; i < scene.instances.size(); ++i)
    side[i] = front_face_sign(scene.instances[i].object_to_world);

  for (size_t t = 0; t < soup.size(); ++t) {
    const scene::Instance& inst = scene.instances[soup.instance[t]];
    const scene::Mesh& mesh = scene.meshes[static_cast<size_t>(inst.mesh)];
    const int material = mesh.triangle_material[soup.mesh_triangle[t]];
    if (material < 0) continue;
    auto it = emitters.find(static_cast<size_t>(material));
    if (it == emitters.end()) continue;
    const EmitterMaterial& e = it->second;

    const Vec3 v0 = soup.v(t, 0), e1 = soup.v(t, 1) - v0, e2 = soup.v(t, 2) - v0;
    // Area and normal in double: slivers at large coordinates keep a sane area.
    const double cx = double(e1.y) * e2.z - double(e1.z) * e2.y;
    const double cy = double(e1.z) * e2.x - double(e1.x) * e2.z;
    const double cz = double(e1.x) * e2.y - double(e1.y) * e2.x;
    const double twice_area = std::sqrt(cx * cx + cy * cy + cz * cz);
    const double n_scale = twice_area > 0 ? side[soup.instance[t]] / twice_area : 0.0;

    LightCandidate c;
    set_type(&c.light, LUX_LIGHT_TYPE_TRIANGLE);
    c.light.origin = {v0.x, v0.y, v0.z, c.light.origin.w};
    c.light.axis = {e1.x, e1.y, e1.z, lux_as_float(static_cast<int32_t>(e.flags))};
    c.light.edge2 = {e2.x, e2.y, e2.z, lux_as_float(static_cast<int32_t>(t))};
    c.light.emission = {e.radiance.x, e.radiance.y, e.radiance.z,
                        static_cast<float>(0.5 * twice_area)};
    c.light.shape = {static_cast<float>(cx * n_scale), static_cast<float>(cy * n_scale),
                     static_cast<float>(cz * n_scale),
                     lux_as_float(static_cast<int32_t>(material))};
    // A triangle whose area rounds to 0 in float would give the device an
    // infinite pdf; power 0 makes build_light_table drop it.
    c.power = LUX_LIGHT_AREA(c.light) > 0 ? 0.5 * twice_area * e.power_scale : 0.0;
    out->push_back(c);
  }
  return Status::ok();
}

}  // namespace luxel::pipeline::detail
