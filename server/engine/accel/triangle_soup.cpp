#include "accel/triangle_soup.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "kernels/shared/texture.h"

namespace luxel::accel {
namespace {

// Alpha mask of one MASK material: the base colour texture's alpha (or a
// constant when the material has no texture), quantized to 8 bits. The
// cutoff is divided by the factor's alpha so the kernel compares texel alpha
// alone: factor.a * tex.a < cutoff  <=>  tex.a < cutoff / factor.a.
cl::LuxAlphaMask make_mask(const scene::Scene& scene, const scene::Material& m,
                           std::vector<uint8_t>& texels) {
  cl::LuxAlphaMask mask{};
  mask.offset = static_cast<int>(texels.size());
  const float factor_a = m.base_color_factor.w;
  mask.cutoff = factor_a > 0 ? m.alpha_cutoff / factor_a : INFINITY;
  const int t = m.base_color_texture.texture;
  if (t >= 0 && t < static_cast<int>(scene.textures.size()) &&
      scene.textures[static_cast<size_t>(t)].has_pixels()) {
    const scene::Texture& tex = scene.textures[static_cast<size_t>(t)];
    mask.width = tex.width;
    mask.height = tex.height;
    auto code = [](scene::WrapMode w) {
      return w == scene::WrapMode::kClampToEdge      ? LUX_WRAP_CLAMP
             : w == scene::WrapMode::kMirroredRepeat ? LUX_WRAP_MIRROR
                                                     : LUX_WRAP_REPEAT;
    };
    mask.wrap =
        LUX_SLOT_MAKE_WRAP(code(m.base_color_texture.wrap_s), code(m.base_color_texture.wrap_t));
    const size_t n = tex.texel_count();
    for (size_t i = 0; i < n; ++i) {
      // 8-bit alpha is the file's code itself; a half is rounded to 8 bits.
      const float a = tex.format == scene::TexelFormat::kRGBA8
                          ? float(tex.rgba8[i * 4 + 3]) / 255.0f
                          : std::clamp(tex.linear(i).w, 0.0f, 1.0f);
      texels.push_back(static_cast<uint8_t>(std::lround((a == a ? a : 0.0f) * 255.0f)));
    }
  } else {
    mask.width = mask.height = 1;
    texels.push_back(255);
  }
  return mask;
}

}  // namespace

Result<TriangleSoup> build_triangle_soup(const scene::Scene& scene) {
  TriangleSoup soup;
  size_t total = 0;
  for (const auto& inst : scene.instances)
    total += scene.meshes[static_cast<size_t>(inst.mesh)].triangle_count();
  if (total > static_cast<size_t>(INT32_MAX))
    return resource_exhausted(
        strprintf("scene has %zu world triangles; at most %d are supported", total, INT32_MAX));

  // Masks per material, created on first use.
  std::map<int, int> mask_of_material;
  auto mask_for = [&](int material) -> int {
    if (material < 0 || material >= static_cast<int>(scene.materials.size())) return -1;
    const auto& m = scene.materials[static_cast<size_t>(material)];
    if (m.alpha_mode != scene::AlphaMode::kMask) return -1;
    auto it = mask_of_material.find(material);
    if (it != mask_of_material.end()) return it->second;
    const int id = static_cast<int>(soup.masks.size());
    soup.masks.push_back(make_mask(scene, m, soup.alpha_texels));
    mask_of_material[material] = id;
    return id;
  };

  soup.vertices.reserve(total * 3);
  soup.instance.reserve(total);
  soup.mesh_triangle.reserve(total);
  soup.alpha_mask.reserve(total);
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    const auto& inst = scene.instances[i];
    const auto& mesh = scene.meshes[static_cast<size_t>(inst.mesh)];
    for (size_t t = 0; t < mesh.triangle_count(); ++t) {
      for (int k = 0; k < 3; ++k) {
        const Vec3 p = transform_point(
            inst.object_to_world, mesh.positions[mesh.indices[t * 3 + static_cast<size_t>(k)]]);
        if (!is_finite(p))
          return invalid_argument(
              strprintf("instance '%s' (node[%d]) of mesh '%s': transform sends triangle %zu to a "
                        "non-finite position",
                        inst.name.c_str(), inst.node_index, mesh.name.c_str(), t));
        soup.vertices.push_back(p);
        soup.bounds.extend(p);
      }
      soup.instance.push_back(static_cast<uint32_t>(i));
      soup.mesh_triangle.push_back(static_cast<uint32_t>(t));
      soup.alpha_mask.push_back(
          mask_for(mesh.triangle_material.empty() ? -1 : mesh.triangle_material[t]));
    }
  }
  if (soup.has_alpha_masks()) {
    // UVs are needed for every triangle index because triangles are addressed
    // by soup index; opaque ones carry zeros and are never sampled.
    soup.uvs.assign(total, cl::LuxTriangleUV{});
    size_t tri = 0;
    for (const auto& inst : scene.instances) {
      const auto& mesh = scene.meshes[static_cast<size_t>(inst.mesh)];
      for (size_t t = 0; t < mesh.triangle_count(); ++t, ++tri) {
        if (soup.alpha_mask[tri] < 0) continue;
        const auto& material = scene.materials[static_cast<size_t>(mesh.triangle_material[t])];
        const scene::TextureRef& ref = material.base_color_texture;
        const auto& uv = mesh.material_uvs(ref.texcoord);
        if (uv.empty()) continue;
        const Vec2 a = ref.transform(uv[mesh.indices[t * 3 + 0]]);
        const Vec2 b = ref.transform(uv[mesh.indices[t * 3 + 1]]);
        const Vec2 c = ref.transform(uv[mesh.indices[t * 3 + 2]]);
        soup.uvs[tri] = {{a.x, a.y}, {b.x, b.y}, {c.x, c.y}, {0, 0}};
      }
    }
  }
  return soup;
}

}  // namespace luxel::accel
