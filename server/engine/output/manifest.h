// The manifest of a baked lightmap: a JSON file beside the images that tells
// an engine everything it needs to use them without guessing (what the
// numbers mean and in which units, which UV set and how instances map into
// the atlas, which file holds what), plus how the bake was made.
//
// JSON layout (version 1): the members of Manifest under the same names, in
// one object with "format": "luxel-lightmap-manifest" and "version": 1.
// Instances are objects {"name", "node", "mesh", "scale": [s, t],
// "offset": [u, v], "rect": [x, y, width, height]}, files are objects
// {"role", "path", "format", "description"}, "settings" is an object of
// strings and "stats" an object. Non-finite stats (JSON has no NaN or Inf) are
// written as null and read back as NaN. Readers ignore members they do not
// know, so version 1 may grow optional members.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "common/status.h"
#include "luxel_version.h"

namespace luxel::output {

inline constexpr const char* kManifestFormat = "luxel-lightmap-manifest";
inline constexpr int kManifestVersion = 1;

struct Manifest {
  std::string luxel_version = LUXEL_VERSION;
  std::string git_revision = LUXEL_GIT_REVISION;
  std::string scene_name;
  std::string scene_sha256;             // hex; may be empty (scene not from the store)
  int width = 0, height = 0;            // lightmap size in texels (both > 0)
  std::string encoding = "irradiance";  // later "sh2", "sg12", ...; not empty
  // What the values are, e.g. "irradiance E in W/m^2 (radiometric; glTF
  // emissive radiance and light intensities taken 1:1)"; not empty.
  std::string units;
  // The TEXCOORD set that holds the lightmap UVs: of the written
  // <scene>_lightmapped.glb when Luxel generated them, else of the input.
  // "TEXCOORD_<n>" when every primitive uses the same set, else "per
  // primitive (extras.lightmapTexCoord)"; uv_sets counts primitives per set.
  std::string uv_set = "TEXCOORD_1";        // not empty
  std::map<std::string, uint64_t> uv_sets;  // "TEXCOORD_<n>" -> primitives; empty: not recorded
  // "shared": every instance uses its TEXCOORD_1 as atlas UV directly (scale
  // 1, offset 0); "packed": Luxel packed per-instance charts, see Instance;
  // "generated": Luxel generated the UVs (uv_layout_json, and the scene
  // written back with them); "placed": the nodes' extras.lightmapScaleOffset.
  std::string atlas_mode = "shared";

  struct Instance {
    std::string name;
    int node = -1;  // glTF node index (-1: none)
    int mesh = -1;  // glTF mesh index (-1: none)
    // atlas_uv = uv1 * scale + offset, in glTF UV convention (v = 0 at the top
    // row of the images); finite.
    float scale[2]{1, 1};
    float offset[2]{0, 0};
    // The instance's texel block in the atlas: x, y (from the top row),
    // width, height; inside the lightmap (its page).
    int rect[4]{0, 0, 0, 0};
    // Lightmap page the instance is on (0..pages-1; scale, offset and rect
    // are relative to that page). Written only when pages > 1.
    int page = 0;
  };
  std::vector<Instance> instances;

  struct File {
    std::string role;    // "irradiance", "preview", "samples", ...; not empty
    std::string path;    // relative to the manifest's folder; not empty
    std::string format;  // e.g. "exr", "png"
    std::string description;
    int page = -1;  // lightmap page of a per-page image; -1 (absent in JSON): not per page
  };
  std::vector<File> files;
  // Lightmap pages (lightmap arrays): each page is width x height and has
  // its own images, "<name>_<page>.<ext>" (files[].page says which); 1 (absent
  // in JSON): one lightmap with plain names.
  int pages = 1;
  // Mean texels per world unit the layout reached (the texel_density asked,
  // or lower where the layout had to fit --max-resolution or --resolution);
  // 0 (absent in JSON): not recorded.
  double texels_per_unit = 0;

  std::map<std::string, std::string> settings;  // bake settings as given
  std::string features;                         // compiled feature list
  std::string device;                           // device description
  // What the importer dropped or could not apply (scene::ImportStats), by
  // name: unsupported extensions, normal maps, samplers; then what the
  // lightmap layout changed from the settings ("lightmap layout: texel
  // density lowered ..."). Empty: none.
  std::vector<std::string> import_warnings;
  std::string intersector;  // backend of the ray queries ("embree", "opencl"; empty: not recorded)
  // Directional encodings: one JSON object each (basis, directions,
  // frame, solver, file), kept as JSON text so the engine's basis description
  // passes through unchanged. Empty for irradiance-only bakes.
  std::vector<std::string> encodings_json;
  // Generated lightmap UVs: one JSON object (why they were generated, chart
  // count, stretch, packing efficiency, density spread, timings; see
  // post/bake_outputs.cpp), kept as JSON text. Empty when the file's
  // TEXCOORD_1 was used.
  std::string uv_layout_json;
  // The denoiser that made the "irradiance_denoised" files: one JSON object
  // (method, iterations, edge-stopping parameters, guides; see
  // post/denoise.h), kept as JSON text. Empty without denoising.
  std::string denoise_json;
  // Seam stitching (output/seam_stitch.h): one JSON object (seam edges,
  // sample points, the bilinear discontinuity along seams before and after,
  // seconds; see post/bake_seams.cpp), kept as JSON text. Empty when
  // seam_stitch is off.
  std::string seam_stitch_json;

  struct Stats {
    double seconds = 0;
    uint64_t paths = 0;
    double mean_spp = 0, min_spp = 0;
    double error_estimate = 0;  // mean relative standard error (DESIGN.md)
    double rmse = -1,
           rel_mse = -1;  // against a reference lightmap; -1 (absent in JSON) without one
    uint64_t nonfinite_dropped = 0;
    std::string termination;  // why the bake stopped: "samples", "time", "error", ...
    size_t covered_texels = 0;
    // Device memory: the bake's buffers at their peak, the budget it was
    // planned within, and the tiles of covered texels it took turns in
    // (0 / absent in JSON: not recorded).
    uint64_t peak_device_bytes = 0, device_memory_budget = 0, tiles = 0;
    uint64_t batch_paths = 0;  // path slots of one iteration (paths_per_iteration resolved)
  } stats;

  int dilation_texels = 0;  // dilation radius applied to the images (>= 0)
};

// The manifest as pretty-printed JSON (2-space indent, trailing newline).
// INVALID_ARGUMENT naming the first field that breaks the rules above.
Result<std::string> manifest_to_json(const Manifest& manifest);

// Parses and validates manifest JSON. `what` names the source in errors.
// DATA_LOSS for text that is not JSON; INVALID_ARGUMENT naming the field
// (e.g. "instances[2].rect") that is missing, has the wrong type or breaks a
// rule, or for another format / an unsupported version.
Result<Manifest> manifest_from_json(const std::string& text, const std::string& what);

// Validates, then writes atomically (common/atomic_file.h). Errors name the path.
Status write_manifest(const std::string& path, const Manifest& manifest);

// Reads and validates; NOT_FOUND for a missing file, otherwise as
// manifest_from_json with the path named.
Result<Manifest> read_manifest(const std::string& path);

}  // namespace luxel::output
