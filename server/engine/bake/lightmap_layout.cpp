#include "bake/lightmap_layout.h"

#include <memory>
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
                                std::string reason, CancelToken cancel) {
  uv::GenerateOptions options;
  options.atlas = settings.atlas;
  options.cancel = cancel;
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

// The scene with the client's placements in place of the nodes' extras.
Result<std::unique_ptr<scene::Scene>> apply_placements(const scene::Scene& scene,
                                                       const std::vector<NodePlacement>& list) {
  auto placed = std::make_unique<scene::Scene>(scene);
  for (size_t i = 0; i < list.size(); ++i) {
    const NodePlacement& np = list[i];
    size_t matched = 0, elements = 0;
    for (scene::Instance& inst : placed->instances) {
      if (inst.node_index != np.node) continue;
      ++elements;
      if (np.element >= 0 && inst.instance_element != np.element) continue;
      inst.has_lightmap_scale_offset = true;
      for (int k = 0; k < 4; ++k) inst.lightmap_scale_offset[k] = np.scale_offset[k];
      inst.lightmap_page = np.page;
      ++matched;
    }
    if (elements == 0)
      return invalid_argument(
          strprintf("settings.placements[%zu].node: node %d is not a baked mesh node of the scene",
                    i, np.node));
    if (matched == 0)
      return invalid_argument(
          strprintf("settings.placements[%zu].instance: node %d has no instance %d (it has %zu)", i,
                    np.node, np.element, elements));
    if (np.element < 0 && matched > 1)
      return invalid_argument(
          strprintf("settings.placements[%zu].instance: node %d has %zu instances "
                    "(EXT_mesh_gpu_instancing); place each one by its instance index",
                    i, np.node, matched));
  }
  return placed;
}

}  // namespace

std::string describe_lightmap_layout(const LightmapLayout& layout) {
  const atlas::Atlas& at = layout.atlas;
  const std::string size =
      strprintf("%dx%d%s, %.3g texels per unit", at.width, at.page_height(),
                at.pages > 1 ? strprintf(", %d pages", at.pages).c_str() : "", at.texels_per_unit);
  if (!layout.generated)
    return strprintf("TEXCOORD_1 of the file, %s atlas, %s", atlas::atlas_mode_name(at.mode),
                     size.c_str());
  const uv::UvReport& u = layout.generated->report;
  return strprintf(
      "generated (%s): %zu charts on %zu meshes in %.2f s (charts %.2f s, packing %.2f s), %s, "
      "packing %.1f %%, stretch L2 %.3f Linf %.3f, %zu overlapping texels",
      layout.generated->reason.c_str(), u.charts, u.meshes, u.total_seconds, u.chart_seconds,
      u.pack_seconds, size.c_str(), 100 * u.efficiency, u.stretch_l2, u.stretch_linf,
      u.overlapping_texels);
}

std::string describe_layout_warnings(const atlas::Atlas& atlas) {
  std::string text;
  for (const std::string& w : atlas.warnings) text += "; warning: " + w;
  return text;
}

Result<LightmapLayout> lay_out_lightmap(const scene::Scene& scene, const BakeSettings& settings,
                                        CancelToken cancel) {
  if (!settings.node_placements.empty()) {
    // Placement dictated by the client through the API: honoured exactly,
    // as the nodes' extras would be (atlas::build_atlas, placed mode).
    auto placed = apply_placements(scene, settings.node_placements);
    if (!placed) return placed.status();
    BakeSettings rest = settings;
    rest.node_placements.clear();
    if (rest.uv == UvMode::kGenerate)
      return invalid_argument(
          "settings.placements: placement maps the file's TEXCOORD_1 into the atlas; it cannot "
          "be combined with --uv generate");
    rest.uv = UvMode::kExisting;
    auto layout = lay_out_lightmap(*placed.value(), rest, cancel);
    if (!layout) return layout.status();
    layout->generated_scene = std::move(placed.value());
    layout->scene = layout->generated_scene.get();
    return layout;
  }
  if (settings.uv == UvMode::kGenerate) return generate(scene, settings, "--uv generate", cancel);
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
  return generate(scene, settings, reason, cancel);
}

}  // namespace luxel::pipeline
