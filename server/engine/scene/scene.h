// The Scene model: what the glTF importer produces and every later stage reads.
//
// Meshes are stored once in object space; instances reference a mesh with a
// world transform (a glTF mesh referenced by several nodes is one Mesh and
// several Instances). Textures are decoded to linear float RGBA on the host.
#pragma once

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
  std::vector<Vec3> normals;               // always present (generated when missing)
  std::vector<Vec4> tangents;              // empty unless the file had TANGENT everywhere
  std::vector<Vec2> uv0;                   // material UVs (TEXCOORD_0); zeros when absent
  std::vector<Vec2> uv1;                   // lightmap UVs (TEXCOORD_1); zeros when absent
  std::vector<uint32_t> indices;           // 3 per triangle
  std::vector<int32_t> triangle_material;  // per triangle; index into Scene::materials
  // Where the vertices and triangles came from in the file, for writing
  // generated lightmap UVs back (pipeline/lightmapped_gltf.h): per triangle
  // primitive of the glTF mesh, its vertex range here (the primitive's
  // vertices in accessor order) and its triangle range here; per triangle,
  // its position in the primitive's triangle list (degenerate ones dropped,
  // so positions may skip).
  struct PrimitiveSpan {
    int primitive = -1;  // index in the glTF mesh's primitives
    uint32_t first_vertex = 0, vertex_count = 0;
    uint32_t first_triangle = 0, triangle_count = 0;
  };
  std::vector<PrimitiveSpan> primitive_spans;
  std::vector<uint32_t> source_triangle;
  bool generated_normals = false;
  // Every primitive had TEXCOORD_1 (otherwise the bake generates lightmap
  // UVs, or refuses with --uv existing; pipeline/lightmap_layout.h).
  bool has_lightmap_uvs = true;
  // Texel centres of a 512^2 grid where TEXCOORD_1 overlaps itself (set by
  // the importer, scene_stats.h find_uv_overlaps); --uv auto regenerates such
  // a mesh's UVs.
  size_t lightmap_uv_overlap_texels = 0;

  size_t triangle_count() const { return indices.size() / 3; }
};

struct Instance {
  std::string name;      // node name, or "node[<index>]"
  int node_index = -1;   // glTF node
  int mesh = -1;         // index into Scene::meshes
  Mat4 object_to_world;  // composed down the node hierarchy
  // The node's extras.lightmapScaleOffset = [sx, sy, ox, oy] (Unity's
  // Renderer.lightmapScaleOffset convention, in glTF UV convention): where
  // the client placed this instance in the atlas, atlas_uv = uv1 * (sx, sy) +
  // (ox, oy). Honoured exactly by the atlas when every instance has one.
  bool has_lightmap_scale_offset = false;
  float lightmap_scale_offset[4] = {1, 1, 0, 0};
};

enum class AlphaMode { kOpaque, kMask, kBlend };

// Reference to a texture used by a material. texture < 0: none.
struct TextureRef {
  int texture = -1;  // index into Scene::textures
  int texcoord = 0;  // which UV set (0 or 1)
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
  TextureRef emissive_texture;     // sRGB in the file, linear here
  float emissive_strength = 1.0f;  // KHR_materials_emissive_strength
  bool double_sided = false;
  AlphaMode alpha_mode = AlphaMode::kOpaque;
  float alpha_cutoff = 0.5f;
  // KHR_materials_ior: index of refraction of the dielectric (the glTF
  // default 1.5 gives f0 = 0.04); 0 is allowed and means f0 = 1.
  float ior = 1.5f;

  // Schlick f0 of the dielectric layer, ((ior - 1) / (ior + 1))^2, in
  // double and rounded once (ior 1.5 gives 0.04f exactly, as Appendix B).
  float dielectric_f0() const {
    if (ior == 0.0f) return 1.0f;
    const double r = (double(ior) - 1.0) / (double(ior) + 1.0);
    return static_cast<float>(r * r);
  }

  bool is_emissive() const {
    return emissive_strength > 0 &&
           (emissive_factor.x > 0 || emissive_factor.y > 0 || emissive_factor.z > 0);
  }
};

enum class ColorSpace { kLinear, kSRGB };

// A decoded texture: linear float RGBA, row 0 at the top of the image (glTF
// UV (0,0) is the top-left corner). One glTF image used both as sRGB colour and
// as linear data becomes two Textures.
struct Texture {
  std::string name;  // image name or uri, or "image[<index>]"
  int gltf_image = -1;
  ColorSpace source_space = ColorSpace::kLinear;  // how the file's values were encoded
  int width = 0, height = 0;
  std::vector<float> rgba;  // width * height * 4, linear
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
