#include "pipeline/lightmap_layout.h"

#include <vector>

namespace luxel::pipeline {
namespace {

// Why the file's TEXCOORD_1 cannot be used, or "" when it can.
std::string missing_lightmap_uvs(const scene::Scene& scene) {
  std::vector<bool> used(scene.meshes.size(), false);
  for (const auto& inst : scene.instances)
    if (inst.mesh >= 0 && static_cast<size_t>(inst.mesh) < scene.meshes.size())
      used[static_cast<size_t>(inst.mesh)] = true;
  size_t missing = 0, overlapping = 0;
  std::string first_missing, first_overlapping;
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    if (!used[m]) continue;
    if (!scene.meshes[m].has_lightmap_uvs && missing++ == 0) first_missing = scene.meshes[m].name;
    if (scene.meshes[m].lightmap_uv_overlap_texels > 0 && overlapping++ == 0)
      first_overlapping = scene.meshes[m].name;
  }
  if (missing == 1) return strprintf("mesh '%s' has no TEXCOORD_1", first_missing.c_str());
  if (missing > 1)
    return strprintf("%zu meshes have no TEXCOORD_1 (first: '%s')", missing, first_missing.c_str());
  if (overlapping == 1)
    return strprintf("the TEXCOORD_1 of mesh '%s' overlaps itself", first_overlapping.c_str());
  if (overlapping > 1)
    return strprintf("the TEXCOORD_1 of %zu meshes overlaps itself (first: '%s')", overlapping,
                     first_overlapping.c_str());
  return "";
}

Result<LightmapLayout> generate(const scene::Scene& scene, const BakeSettings& settings,
                                std::string reason) {
  uv::GenerateOptions options;
  options.atlas = settings.atlas;
  auto gen = uv::generate_lightmap_uvs(scene, options);
  if (!gen) return gen.status();
  uv::GeneratedUvs& g = gen.value();
  LightmapLayout layout;
  auto uvs = std::make_shared<GeneratedUvLayout>();
  uvs->report = g.report;
  uvs->reason = std::move(reason);
  uvs->meshes.resize(g.scene.meshes.size());
  for (size_t m = 0; m < g.scene.meshes.size(); ++m) {
    if (g.vertex_origin[m].empty()) continue;
    GeneratedUvLayout::MeshUvs& mu = uvs->meshes[m];
    mu.indices = g.scene.meshes[m].indices;
    mu.uv1 = g.scene.meshes[m].uv1;
    mu.vertex_origin = std::move(g.vertex_origin[m]);
  }
  layout.atlas = std::move(g.atlas);
  layout.generated_scene = std::make_unique<scene::Scene>(std::move(g.scene));
  layout.scene = layout.generated_scene.get();
  layout.generated = std::move(uvs);
  return layout;
}

}  // namespace

Result<LightmapLayout> lay_out_lightmap(const scene::Scene& scene, const BakeSettings& settings) {
  if (settings.uv == UvMode::kGenerate) return generate(scene, settings, "--uv generate");
  std::string reason = missing_lightmap_uvs(scene);
  if (reason.empty()) {
    auto atlas = atlas::build_atlas(scene, settings.atlas);
    if (atlas) {
      LightmapLayout layout;
      layout.scene = &scene;
      layout.atlas = std::move(atlas.value());
      return layout;
    }
    // Only a problem with the UVs themselves falls back to generation; a
    // setting or size problem stays an error.
    if (settings.uv == UvMode::kExisting || atlas.status().code() != StatusCode::kInvalidArgument ||
        scene.instances.empty())
      return atlas.status();
    reason = atlas.status().message();
  } else if (settings.uv == UvMode::kExisting) {
    // Overlapping UVs are baked as they are (the import warning names them);
    // missing ones cannot be.
    if (reason.find("no TEXCOORD_1") != std::string::npos)
      return invalid_argument(reason +
                              " (lightmap UVs); bake with --uv auto or generate to "
                              "have them generated");
    auto atlas = atlas::build_atlas(scene, settings.atlas);
    if (!atlas) return atlas.status();
    LightmapLayout layout;
    layout.scene = &scene;
    layout.atlas = std::move(atlas.value());
    return layout;
  }
  return generate(scene, settings, reason);
}

}  // namespace luxel::pipeline
