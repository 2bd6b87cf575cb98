// The lightmap atlas: where each instance's TEXCOORD_1 layout lands in the
// one lightmap image of a bake (thesis §4.1-4.2: "the clip-space position for
// each mesh vertex within the lightmap is given by the vertex's lightmap UV
// transformed by the offset and scale produced in the preprocessing stage").
//
// Two modes:
//   kShared  the scene already has one scene-wide atlas in TEXCOORD_1 (every
//            mesh used by at most one instance, layouts of different
//            instances disjoint; the shared benchmark scenes): UVs are used
//            as they are (scale 1, offset 0).
//   kPacked  otherwise (instanced meshes, per-mesh layouts that each fill the
//            unit square): every instance gets its own rectangle, its mesh's
//            TEXCOORD_1 bounding box scaled to one texel density for the whole
//            scene (see shelf_packer.h).
//   kGenerated lightmap UVs were generated (uv/generate.h): charts of every
//            mesh packed at one texel density; a mesh used once carries atlas
//            UVs (scale 1, offset 0), an instanced mesh one layout placed per
//            instance by scale and offset as in kPacked.
//   kPlaced  every instance's node carries extras.lightmapScaleOffset (a
//            client such as an editor plugin owns the layout, or the scene
//            was written back by Luxel): each instance's TEXCOORD_1 goes
//            exactly where its scale and offset put it; texel centres covered
//            by two instances are an INVALID_ARGUMENT naming both nodes.
//
// UV convention: glTF UV (0,0) is the top-left corner; atlas UV (u, v) is the
// point (u * width, v * height) in texel units, row 0 at the top. Texel (x, y)
// covers [x, x+1) x [y, y+1).
//
// In shared mode every TEXCOORD_1 must lie in [0,1] (a tolerance of 1e-5):
// clamping would fold geometry onto the border texels, so a UV outside is an
// INVALID_ARGUMENT naming the mesh. (A scene whose layouts overlap is packed
// instead, and packing accepts any UV range.)
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/math.h"
#include "common/status.h"
#include "scene/scene.h"

namespace luxel::atlas {

// The lightmap size a bake gets when it names none (settings schema:
// texel_density and max_resolution). 40 texels per world unit (metre, in
// glTF) is Unity's default lightmap resolution (LightingSettings.
// lightmapResolution) and 1024 its default largest lightmap
// (LightingSettings.lightmapMaxSize): a 1 m wall gets 40x40 texels, about
// 2.5 cm each, fine enough for contact shadows at room scale, while a large
// scene is held to 1024^2 texels a page (4x the fixed 512^2 of earlier
// releases) and its bake time stays bounded unless asked otherwise.
inline constexpr float kDefaultTexelDensity = 40;
inline constexpr int kDefaultMaxResolution = 1024;
// The largest side the engine lays out (luxeld lowers it: --max-resolution).
inline constexpr int kResolutionLimit = 8192;

struct AtlasSettings {
  int resolution = 0;       // square side in texels (per page); 0: derive from texel_density
  float texel_density = 0;  // texels per world unit, used when resolution == 0
  int padding_texels = 2;   // packed mode: between rectangles and from the border
  // Largest page side a texel density may give: past it generated UVs go on
  // more pages and the file's TEXCOORD_1 gets a lower density (with a
  // warning, Atlas::warnings). An explicit resolution is not bound by it.
  int max_resolution = kResolutionLimit;
  // Largest side of any page, explicit resolutions too: larger is
  // RESOURCE_EXHAUSTED (the engine's limit, or the daemon's --max-resolution).
  int resolution_limit = kResolutionLimit;
};

enum class AtlasMode { kShared, kPacked, kGenerated, kPlaced };

const char* atlas_mode_name(AtlasMode mode);

struct InstancePlacement {
  uint32_t instance = 0;
  int page = 0;  // lightmap page (Atlas::pages); scale/offset/rect are in the stacked image
  float scale[2] = {1, 1};  // atlas_uv = uv1 * scale + offset
  float offset[2] = {0, 0};
  int rect[4] = {0, 0, 0, 0};  // x, y, w, h in texels (the whole atlas in shared mode)
};

struct Atlas {
  int width = 0, height = 0;
  AtlasMode mode = AtlasMode::kShared;
  std::vector<InstancePlacement> placements;  // one per Scene::instances, same order
  double texels_per_unit = 0;                 // achieved mean density (texels per world unit)
  // Lightmap pages (generated layouts past max_resolution): `pages` squares
  // of width x (height / pages) stacked from the top; the bake treats them as
  // one image and the outputs cut it into pages (post/bake_outputs.h).
  int pages = 1;
  int page_height() const { return height / pages; }
  // What the layout changed from what was asked, for the CLI, the daemon's
  // status and the manifest ("texel density lowered from 40 to 12.5 texels
  // per unit to fit the 1024x1024 page (--max-resolution)").
  std::vector<std::string> warnings;

  Vec2 to_atlas(uint32_t instance, Vec2 uv1) const {
    const InstancePlacement& p = placements[instance];
    return {uv1.x * p.scale[0] + p.offset[0], uv1.y * p.scale[1] + p.offset[1]};
  }
};

// A placement relative to its page (what the manifest and the written-back
// glTF give: atlas_uv on the page = uv1 * scale + offset, rect on the page).
// The identity for a one-page atlas.
inline InstancePlacement page_relative(const Atlas& atlas, InstancePlacement p) {
  if (atlas.pages <= 1) return p;
  const double pages = atlas.pages;
  p.scale[1] = static_cast<float>(double(p.scale[1]) * pages);
  p.offset[1] = static_cast<float>(double(p.offset[1]) * pages - p.page);
  p.rect[1] -= atlas.page_height() * p.page;
  return p;
}

// Lays out the scene's lightmap. With resolution > 0 the atlas is that square
// (texel_density is ignored); packed mode then uses the largest density that
// fits. With resolution == 0 the side follows from texel_density: in shared
// mode ceil(sqrt(world area * density^2 / UV area)), in packed mode the
// smallest multiple of 4 that holds the charts; past max_resolution the
// side is max_resolution and the density lower (the file's UVs are one
// atlas, so they cannot be paged), with a warning.
// Errors: INVALID_ARGUMENT naming the setting or the mesh (missing, non-finite
// or all zero-area TEXCOORD_1; UVs outside [0,1] in shared mode), "scene has
// no geometry" without instances; RESOURCE_EXHAUSTED naming the limit
// (resolution_limit) and the size asked.
Result<Atlas> build_atlas(const scene::Scene& scene, const AtlasSettings& settings);

}  // namespace luxel::atlas
