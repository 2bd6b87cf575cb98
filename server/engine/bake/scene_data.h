// Host-side preparation of the per-bake device data that is not the BVH:
// per-triangle surface records (positions, shading normals, material UVs,
// material, emissive light, instance), device materials, tangents for
// normal-mapped materials, atlas-space
// triangle UVs for primary rays, and the instance -> first world triangle
// table that turns sample-info records (instance, mesh triangle) into world
// triangle ids (TriangleSoup order). Also derives the bake's FeatureSet.
#pragma once

#include <cstdint>
#include <vector>

#include "accel/triangle_soup.h"
#include "atlas/atlas.h"
#include "common/status.h"
#include "device/feature_set.h"
#include "kernels/shared/bake.h"
#include "kernels/shared/geometry.h"
#include "scene/scene.h"
#include "settings/bake_settings.h"

namespace luxel::pipeline {

struct SceneData {
  std::vector<cl::LuxSurfaceTri> surface;    // per world triangle
  std::vector<cl::LuxTriangleUV> atlas_uvs;  // per world triangle, atlas UV in [0,1]
  std::vector<cl::LuxMaterial> materials;
  // Per world triangle, material UV set 1 (TEXCOORD_1 as in the file); empty
  // unless uses_texcoord1.
  std::vector<cl::LuxTriangleUV> material_uv1;
  // Per world triangle, world-space vertex tangents; empty unless
  // uses_normal_map.
  std::vector<cl::LuxTriangleTangents> tangents;
  std::vector<uint32_t> instance_first;  // per instance
  bool uses_textures = false;            // a base colour or metallic-roughness texture is used
  bool uses_emissive_texture = false;
  bool uses_texcoord1 = false;   // some material texture reads TEXCOORD_1
  bool uses_normal_map = false;  // some used material has a normal texture
  bool needs_specular = false;   // some used material is not a rough dielectric
};

// `triangle_light`: per world triangle, emissive light index or -1 (from the
// light table).
Result<SceneData> prepare_scene_data(const scene::Scene& scene, const accel::TriangleSoup& soup,
                                     const atlas::Atlas& atlas,
                                     const std::vector<int32_t>& triangle_light);

}  // namespace luxel::pipeline
