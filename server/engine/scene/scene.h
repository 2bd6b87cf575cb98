// The Scene model: what the glTF importer produces and every later stage reads.
//
// Meshes are stored once in object space; instances reference a mesh with a
// world transform (a glTF mesh referenced by several nodes is one Mesh and
// several Instances). Textures keep the file's 8-bit codes (RGBA8) or, for
// 16-bit images, linear half floats: 4 or 8 bytes per texel.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "common/math.h"

namespace luxel::scene {

// A triangle mesh (all triangle primitives of one glTF mesh, concatenated).
// Degenerate and zero-area triangles were dropped during import (counted in
// ImportStats). Vertex attributes are parallel arrays of equal length.
struct Mesh {
  std::string name;     // glTF mesh name, or "mesh[<index>]"
  int gltf_index = -1;  // index in the glTF meshes array
  std::vector<Vec3> positions;
  std::vector<Vec3> normals;  // always present (generated when missing)
  // Per vertex, xyz = unit tangent (+U of the normal texture's UV set),
  // w = bitangent sign (bitangent = cross(normal, tangent) * w, glTF 2.0
  // §3.7.2.1 TANGENT). Empty unless a triangle's material has a normal
  // texture; then from TANGENT where the primitive has it, generated
  // (scene/tangents.h) elsewhere, and (0, 0, 0, 1) on vertices of primitives
  // without a normal map.
  std::vector<Vec4> tangents;
  std::vector<Vec2> uv0;                   // material UVs (TEXCOORD_0); zeros when absent
  std::vector<Vec2> uv1;                   // lightmap UVs (TEXCOORD_1); zeros when absent
  std::vector<uint32_t> indices;           // 3 per triangle
  std::vector<int32_t> triangle_material;  // per triangle; index into Scene::materials
  // Where the vertices and triangles came from in the file, for writing
  // generated lightmap UVs back (post/lightmapped_gltf.h): per triangle
  // primitive of the glTF mesh, its vertex range here (the primitive's
  // vertices in accessor order) and its triangle range here; per triangle,
  // its position in the primitive's triangle list (degenerate ones dropped,
  // so positions may skip).
  struct PrimitiveSpan {
    int primitive = -1;  // index in the glTF mesh's primitives
    // TEXCOORD index read as lightmap UVs (extras.lightmapTexCoord, else 1)
    int lightmap_texcoord = 1;
    bool has_lightmap_uvs = true;  // the primitive has that set
    uint32_t first_vertex = 0, vertex_count = 0;
    uint32_t first_triangle = 0, triangle_count = 0;
  };
  std::vector<PrimitiveSpan> primitive_spans;
  std::vector<uint32_t> source_triangle;
  bool generated_normals = false;
  // Every primitive had TEXCOORD_1 (otherwise the bake generates lightmap
  // UVs, or refuses with --uv existing; bake/lightmap_layout.h).
  bool has_lightmap_uvs = true;
  // Texel centres of a 512^2 grid where TEXCOORD_1 overlaps itself (set by
  // the importer, scene_stats.h find_uv_overlaps); --uv auto regenerates such
  // a mesh's UVs.
  size_t lightmap_uv_overlap_texels = 0;

  size_t triangle_count() const { return indices.size() / 3; }
  // TEXCOORD_1 as in the file (zeros where a primitive lacks it) when uv1
  // holds other UVs: generated lightmap UVs (uv/generate.h keeps it, seam
  // copies included), or a primitive's lightmap set is not TEXCOORD_1
  // (PrimitiveSpan::lightmap_texcoord); empty otherwise.
  std::vector<Vec2> file_uv1;
  // The UV set a material texture with texCoord `set` reads: TEXCOORD_0 or
  // TEXCOORD_1 exactly as in the file (never generated lightmap UVs).
  const std::vector<Vec2>& material_uvs(int set) const {
    if (set != 1) return uv0;
    return file_uv1.empty() ? uv1 : file_uv1;
  }
};

struct Instance {
  std::string name;           // node name, or "node[<index>]"
  int node_index = -1;        // glTF node
  int instance_element = -1;  // EXT_mesh_gpu_instancing element of the node; -1: none
  int mesh = -1;              // index into Scene::meshes
  Mat4 object_to_world;       // composed down the node hierarchy
  // The node's extras.lightmapScaleOffset = [sx, sy, ox, oy] (Unity's
  // Renderer.lightmapScaleOffset convention, in glTF UV convention): where
  // the client placed this instance in the atlas, atlas_uv = uv1 * (sx, sy) +
  // (ox, oy). Honoured exactly by the atlas when every instance has one.
  bool has_lightmap_scale_offset = false;
  float lightmap_scale_offset[4] = {1, 1, 0, 0};
  int lightmap_page = 0;  // extras.lightmapIndex: the lightmap page (array layer)
};

enum class AlphaMode { kOpaque, kMask, kBlend };

// Sampler wrap mode (glTF 2.0 §5.26 sampler.wrapS / wrapT).
enum class WrapMode { kRepeat, kClampToEdge, kMirroredRepeat };

// Reference to a texture used by a material (a glTF textureInfo with its
// texture's sampler and KHR_texture_transform). texture < 0: none.
struct TextureRef {
  int texture = -1;  // index into Scene::textures
  int texcoord =
      0;  // UV set read (0 or 1); KHR_texture_transform's texCoord overrides the textureInfo's
  WrapMode wrap_s = WrapMode::kRepeat;
  WrapMode wrap_t = WrapMode::kRepeat;
  // KHR_texture_transform (absent: identity).
  bool has_transform = false;
  Vec2 offset{0, 0};
  float rotation = 0;  // radians, counter-clockwise in UV space
  Vec2 scale{1, 1};

  // The extension's matrix T * R * S as rows (m00 m01 m02; m10 m11 m12):
  // uv' = (m00 u + m01 v + m02, m10 u + m11 v + m12), with
  // T = [1 0 ox; 0 1 oy], R = [cos sin; -sin cos], S = diag(sx, sy).
  std::array<double, 6> uv_matrix() const {
    const double c = std::cos(double(rotation)), s = std::sin(double(rotation));
    const double sx = scale.x, sy = scale.y;
    return {c * sx, s * sy, double(offset.x), -s * sx, c * sy, double(offset.y)};
  }
  Vec2 transform(Vec2 uv) const {
    if (!has_transform) return uv;
    const auto m = uv_matrix();
    return {static_cast<float>(m[0] * uv.x + m[1] * uv.y + m[2]),
            static_cast<float>(m[3] * uv.x + m[4] * uv.y + m[5])};
  }
};

// glTF pbrMetallicRoughness plus emission; factors multiply textures.
struct Material {
  std::string name;
  Vec4 base_color_factor{1, 1, 1, 1};
  TextureRef base_color_texture;  // sRGB in the file, linear here
  float metallic_factor = 1.0f;
  float roughness_factor = 1.0f;
  TextureRef metallic_roughness_texture;  // G = roughness, B = metallic (linear)
  Vec3 emissive_factor{0, 0, 0};
  TextureRef emissive_texture;  // sRGB in the file, linear here
  // Tangent-space normal map (linear; glTF 2.0 §3.9.3): n = normalize(
  // (2 rgb - 1) * (scale, scale, 1)) in the frame (tangent, bitangent, normal).
  TextureRef normal_texture;
  float normal_scale = 1.0f;       // normalTextureInfo.scale
  float emissive_strength = 1.0f;  // KHR_materials_emissive_strength
  bool double_sided = false;
  AlphaMode alpha_mode = AlphaMode::kOpaque;
  float alpha_cutoff = 0.5f;
  // KHR_materials_ior: index of refraction of the dielectric (the glTF
  // default 1.5 gives f0 = 0.04); 0 is allowed and means f0 = 1.
  float ior = 1.5f;
  // KHR_materials_specular: strength and colour of the dielectric's specular
  // reflection (defaults: no change).
  float specular_factor = 1.0f;
  Vec3 specular_color_factor{1, 1, 1};

  // Schlick f0 of the dielectric layer, ((ior - 1) / (ior + 1))^2, in
  // double and rounded once (ior 1.5 gives 0.04f exactly, as Appendix B).
  float dielectric_f0() const {
    if (ior == 0.0f) return 1.0f;
    const double r = (double(ior) - 1.0) / (double(ior) + 1.0);
    return static_cast<float>(r * r);
  }

  // The dielectric's specular F0 and F90 after KHR_materials_specular:
  // F0 = min(F0(ior) * specularColorFactor, 1) * specularFactor and
  // F90 = specularFactor (the extension's dielectric_f0 / dielectric_f90).
  // Without the extension: F0(ior) in every channel, F90 = 1.
  Vec3 dielectric_specular_f0() const {
    const float f = dielectric_f0();
    if (specular_factor == 1.0f && specular_color_factor.x == 1.0f &&
        specular_color_factor.y == 1.0f && specular_color_factor.z == 1.0f)
      return {f, f, f};
    auto c = [&](float k) { return std::min(f * k, 1.0f) * specular_factor; };
    return {c(specular_color_factor.x), c(specular_color_factor.y), c(specular_color_factor.z)};
  }
  float dielectric_specular_f90() const { return specular_factor; }

  bool is_emissive() const {
    return emissive_strength > 0 &&
           (emissive_factor.x > 0 || emissive_factor.y > 0 || emissive_factor.z > 0);
  }
};

enum class ColorSpace { kLinear, kSRGB };

// How a decoded Texture stores its texels.
enum class TexelFormat {
  kRGBA8,    // the file's 8-bit codes: rgb sRGB-encoded when source_space is kSRGB
  kRGBA16F,  // IEEE binary16, already linear (16-bit images, decoded through the EOTF)
};

// A decoded texture, row 0 at the top of the image (glTF UV (0,0) is the
// top-left corner). One glTF image used both as sRGB colour and as linear
// data becomes two Textures. Alpha is always linear. 8-bit images keep their
// codes so host and device hold 4 bytes per texel (decoded to linear where
// read: Texture::linear here, kernels/shading/texture.h on the device).
struct Texture {
  std::string name;  // image name or uri, or "image[<index>]"
  int gltf_image = -1;
  ColorSpace source_space = ColorSpace::kLinear;  // how the file's values were encoded
  int width = 0, height = 0;
  TexelFormat format = TexelFormat::kRGBA8;
  std::vector<uint8_t> rgba8;     // kRGBA8: width * height * 4 codes
  std::vector<uint16_t> rgba16f;  // kRGBA16F: width * height * 4 halves, linear

  size_t texel_count() const {
    return size_t(width > 0 ? width : 0) * size_t(height > 0 ? height : 0);
  }
  // Whether the pixels were decoded and match the size (import without
  // decoding keeps only the size).
  bool has_pixels() const {
    const size_t n = texel_count() * 4;
    return n > 0 && (format == TexelFormat::kRGBA8 ? rgba8.size() : rgba16f.size()) == n;
  }
  // Linear RGBA of texel i (row-major); requires has_pixels().
  Vec4 linear(size_t i) const;
  size_t pixel_bytes() const { return rgba8.size() + rgba16f.size() * sizeof(uint16_t); }
};

enum class LightType { kPoint, kSpot, kDirectional };

// KHR_lights_punctual, in the extension's photometric units:
// point/spot intensity in candela (lm/sr), directional in lux (lm/m^2).
struct Light {
  std::string name;
  LightType type = LightType::kPoint;
  Vec3 color{1, 1, 1};  // linear RGB
  float intensity = 1.0f;
  float range = 0.0f;             // 0: infinite
  float inner_cone_angle = 0.0f;  // radians, spot only
  float outer_cone_angle = 0.785398f;
  Vec3 position{0, 0, 0};    // world space (point, spot)
  Vec3 direction{0, 0, -1};  // world space, unit, direction the light points
  int node_index = -1;
};

// What the importer dropped, skipped or generated; reported, never fatal.
struct ImportStats {
  size_t degenerate_triangles_dropped = 0;  // repeated index or zero-area
  size_t skipped_primitives = 0;            // points and lines (strips and fans become triangles)
  std::vector<std::string> warnings;        // human-readable, name the node/mesh/primitive
  // Most bytes the import held reserved at once (scene/import_budget.h): the
  // smallest ImportOptions::max_import_bytes that accepts the file.
  uint64_t peak_reserved_bytes = 0;
};

struct Scene {
  std::string source_name;  // file name as given
  std::vector<Mesh> meshes;
  std::vector<Instance> instances;
  std::vector<Material>
      materials;  // always at least one (the glTF default material is appended when used)
  std::vector<Texture> textures;
  std::vector<Light> lights;
  ImportStats import_stats;
};

}  // namespace luxel::scene
