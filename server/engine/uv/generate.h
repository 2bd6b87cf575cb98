// Generated lightmap UVs for a whole scene: the charts of every baked mesh
// (charts.h) packed into one atlas at one world-space texel density
// (bitimage_packer.h, thesis §4.1), then assembled into TEXCOORD_1 with the
// vertices on chart seams split.
//
// Layout rules:
//   - A mesh used by one instance packs its charts one by one, each free to
//     turn by quarter turns, scaled by that instance's world size; its new
//     TEXCOORD_1 are atlas UVs (placement scale 1, offset 0).
//   - A mesh used by several instances keeps one set of UVs: its charts are
//     packed once into a layout of its own (at the smallest instance's
//     scale, so the padding holds for every instance), and that layout is
//     placed per instance, scaled to the instance's world size, by scale and
//     offset (atlas_uv = uv1 * scale + offset, as AtlasMode::kPacked).
//   - With AtlasSettings::resolution the density is the largest (within 3 %)
//     whose packing fits; when none does (every chart keeps a texel and its
//     padding), several pages of that size. With texel_density the atlas is
//     the smallest square that holds the charts, or, past max_resolution,
//     several pages of max_resolution squared, each holding whole instances
//     (lightmap arrays); past max_pages, at a lower density. Either fallback
//     leaves a warning in GeneratedUvs::atlas.warnings.
// Deterministic: the same scene and settings give the same bits.
#pragma once

#include <cstdint>
#include <vector>

#include "atlas/atlas.h"
#include "common/cancel.h"
#include "common/status.h"
#include "scene/scene.h"
#include "uv/charts.h"

namespace luxel::uv {

struct GenerateOptions {
  atlas::AtlasSettings atlas;  // resolution or texel_density, padding, max_resolution
  ChartOptions charts;
  // A layout larger than one page goes on up to this many pages (lightmap
  // arrays) of max_resolution squared (texel_density) or of the resolution
  // asked (when the charts fit it at no density); 1: RESOURCE_EXHAUSTED
  // instead.
  int max_pages = 64;
  // Polled per mesh while charting and per packing tried: a request ends
  // the generation with cancelled_error (common/cancel.h).
  CancelToken cancel;
};

// What `luxel inspect --uv` and the manifest report about a generated layout.
struct UvReport {
  size_t meshes = 0;              // meshes given new UVs
  size_t charts = 0;              // charts over those meshes
  size_t triangles = 0;           // triangles laid out
  size_t unplaced_triangles = 0;  // degenerate triangles left out of every chart
  size_t seam_vertices = 0;       // vertices added by splitting on chart seams
  // Stretch (Sander et al. 2001) of the map from 3D to UV, after the charts'
  // area normalisation: area-weighted L2 over all triangles (1 = none) and
  // the largest L-infinity of any triangle.
  double stretch_l2 = 1, stretch_linf = 1;
  double efficiency = 0;  // covered texels / atlas texels (packer's masks)
  // Largest / smallest achieved texels per world unit over instances,
  // sqrt(texel area / world area) measured on the final UVs.
  double density_spread = 1;
  int pack_attempts = 0;  // packings tried while searching the density
  int pages = 1;          // lightmap pages (atlas::Atlas::pages)
  // Texel centres inside two or more laid-out triangles (any instances);
  // required to be 0.
  size_t overlapping_texels = 0;
  double chart_seconds = 0, pack_seconds = 0, total_seconds = 0;
};

struct GeneratedUvs {
  scene::Scene scene;  // the input with split vertices and generated uv1 on laid-out meshes
  atlas::Atlas atlas;  // mode kGenerated
  // Per mesh: the input vertex each vertex was copied from (empty for a mesh
  // that was not laid out). The first copy of input vertex v is vertex v, so a
  // writer can keep the file's vertex data and append the seam copies.
  std::vector<std::vector<uint32_t>> vertex_origin;
  UvReport report;
};

// Errors: INVALID_ARGUMENT for bad settings or a scene without instances or
// without any triangle that can be laid out (points and lines only);
// RESOURCE_EXHAUSTED naming the option to change when an instance does not
// fit one page at any density tried.
Result<GeneratedUvs> generate_lightmap_uvs(const scene::Scene& scene,
                                           const GenerateOptions& options);

}  // namespace luxel::uv
