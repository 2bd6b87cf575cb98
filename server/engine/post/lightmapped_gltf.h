// Writes generated lightmap UVs back into the scene file, so an engine can
// use the lightmap: `<scene>_lightmapped.glb` is the input glTF with
//   - the generated UVs in a TEXCOORD set of every laid-out primitive, the
//     vertices that chart seams split appended at the end of each
//     primitive's vertex list (every other attribute and morph target copied
//     for them) and the index list rewritten to use them. The set is
//     TEXCOORD_1 unless the primitive has it or a material reads it; then the
//     first free index above. No set the file has or its materials read is
//     overwritten, except one an earlier write-back recorded as its lightmap.
//     Missing sets below the lightmap's are added as zeros, so the indices
//     stay contiguous (glTF 2.0 §3.7.2.1). The index is recorded on the
//     primitive as extras.lightmapTexCoord (the importer reads it back,
//     scene/mesh_build.cpp);
//   - on every baked node, extras.lightmapScaleOffset = [sx, sy, ox, oy]:
//     atlas_uv = uv * (sx, sy) + (ox, oy) in glTF UV convention (Unity's
//     Renderer.lightmapScaleOffset), uv the primitive's lightmap set. A node
//     that instantiates several instances (EXT_mesh_gpu_instancing) gets
//     extras.lightmapScaleOffsets, one entry per instance in the extension's
//     order. With several lightmap pages the scale/offset are relative to the
//     instance's page and extras.lightmapIndex (lightmapIndices) names the
//     page.
// Everything else survives as it was in the JSON: nodes, materials, textures,
// extensions, extras, unknown members. The file is always a GLB: buffers
// (external, data URIs, the GLB chunk) are merged into its one binary chunk,
// and external image files are embedded (scene/gltf_document.h).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "bake/bake.h"
#include "common/status.h"
#include "scene/scene.h"

namespace luxel::pipeline {

struct WritebackReport {
  size_t primitives = 0;                      // primitives given generated lightmap UVs
  std::map<int, size_t> texcoord_primitives;  // TEXCOORD index -> primitives with the lightmap
  size_t filler_sets = 0;                     // zero TEXCOORD sets added below the lightmap's
  size_t added_vertices = 0;                  // seam copies appended over all primitives
  size_t nodes = 0;                           // nodes given extras.lightmapScaleOffset(s)
  std::vector<std::string> warnings;          // what could not be written, by name
};

// `source_path` is the file the scene was imported from (.gltf or .glb;
// external files resolve beside it), `scene` the imported scene (not the
// layout's split copy), `result` the bake, which must carry uv_layout.
// Errors: INVALID_ARGUMENT when the bake has no generated UVs or the file
// does not match the scene; NOT_FOUND / DATA_LOSS for unreadable inputs;
// the output is written atomically.
Result<WritebackReport> write_lightmapped_glb(const std::string& source_path,
                                              const scene::Scene& scene, const BakeResult& result,
                                              const std::string& out_path);

// The same from memory; `base_dir` resolves external URIs ("" refuses them).
Result<std::string> lightmapped_glb_bytes(std::string_view source, const std::string& base_dir,
                                          const scene::Scene& scene, const BakeResult& result,
                                          WritebackReport* report);

}  // namespace luxel::pipeline
