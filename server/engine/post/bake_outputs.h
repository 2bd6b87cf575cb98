// Writes a finished bake into a folder: the irradiance lightmap (linear float
// EXR, alpha = coverage), its denoised twin (settings.denoise), a tone-mapped
// PNG preview, the samples-per-texel and relative-error maps, one EXR of
// coefficients per directional encoding, the error-against-time series (CSV)
// and a JSON manifest describing all of them. Uncovered texels are dilated
// first so bilinear filtering in an engine does not bleed black into charts.
#pragma once

#include <string>
#include <vector>

#include "bake/bake.h"
#include "common/status.h"
#include "output/manifest.h"
#include "scene/scene.h"

namespace luxel::pipeline {

struct OutputPaths {
  std::string irradiance_exr, preview_png, samples_exr, error_exr, series_csv, manifest_json;
  std::vector<std::string> encodings;   // one EXR per directional encoding ("sh2.exr", ...)
  std::string lightmapped_glb;          // "<scene>_lightmapped.glb"; empty without generated UVs
  std::string irradiance_denoised_exr;  // settings.denoise != off; empty otherwise
  // A shard of a distributed bake (result.final_state): "accumulators.bin",
  // its per-texel accumulators in the checkpoint format (write_checkpoint);
  // empty otherwise.
  std::string accumulators_bin;
  // Every file written, by name in `dir` (a multi-page lightmap has
  // "irradiance_<page>.exr", ...; the fields above then name page 0's).
  std::vector<std::string> files;
};

// "<stem of the scene's file name>_lightmapped.glb" (characters outside
// [A-Za-z0-9._-] become '_'): the scene with its generated UVs
// (lightmapped_gltf.h).
std::string lightmapped_glb_name(const std::string& scene_file_name);

// Creates `dir` if needed. `scene_sha256` may be empty. With generated UVs
// (result.uv_layout) and the scene's file at `source_path`, also writes the
// scene with those UVs as lightmapped_glb_name(scene_name), where
// `scene_name` is the name the user knows the scene by (the daemon stores
// uploads under fixed file names; empty: scene.source_name).
Result<OutputPaths> write_bake_outputs(const std::string& dir, const scene::Scene& scene,
                                       const BakeSettings& settings, const BakeResult& result,
                                       const std::string& scene_sha256 = "",
                                       const std::string& source_path = "",
                                       const std::string& scene_name = "");

// The same files from a result the caller is done with: a one-page
// result's images are moved out and released as each file is written, so
// output assembly holds no second full-size copy of them (the figures,
// atlas, manifest entries and final state stay).
Result<OutputPaths> write_bake_outputs_releasing(const std::string& dir, const scene::Scene& scene,
                                                 const BakeSettings& settings, BakeResult& result,
                                                 const std::string& scene_sha256 = "",
                                                 const std::string& source_path = "",
                                                 const std::string& scene_name = "");

// The manifest that write_bake_outputs writes (without the file list).
output::Manifest make_manifest(const scene::Scene& scene, const BakeSettings& settings,
                               const BakeResult& result, const std::string& scene_sha256);

}  // namespace luxel::pipeline
