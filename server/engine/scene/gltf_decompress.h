// Compressed glTF geometry decoded into plain glTF, at the JSON level, once,
// for every reader of a file Luxel did not write (the importer, through
// scene/gltf_load.cpp, and the write-back of lightmap UVs,
// post/lightmapped_gltf.cpp). Two extensions are decoded:
//
// - KHR_draco_mesh_compression (primitives): the Draco bitstream of the
//   extension's bufferView is decoded with Draco's decoder; every accessor
//   the extension's `attributes` map names, and the primitive's `indices`,
//   become plain accessors on new bufferViews with the decoded data (the
//   extension's README, "accessors": they must match the decompressed data,
//   so a declared count that differs is an error). Triangle strips come out
//   as triangle lists (mode 4): Draco decodes faces. Attributes the
//   extension does not name are kept as they are ("Conformance").
// - EXT_meshopt_compression (bufferViews): the view's bytes are decoded from
//   the extension's source range with meshoptimizer (modes ATTRIBUTES,
//   TRIANGLES, INDICES; filters NONE, OCTAHEDRAL, QUATERNION, EXPONENTIAL),
//   appended to the buffer, and the view points to them. Fallback buffers
//   (the README's "Fallback buffers") are never read
//   (scene/gltf_document.h).
//
// The result uses neither extension: each is removed from the primitives,
// bufferViews and buffers, and from extensionsUsed / extensionsRequired.
// Everything else is unchanged. Errors name the mesh and primitive or the
// bufferView and say what is wrong; a corrupt stream is INVALID_ARGUMENT,
// more decoded elements than `max_elements` is RESOURCE_EXHAUSTED, refused
// before Luxel allocates the decoded data. (Draco's decoder itself allocates
// as its bitstream says before the decoded counts can be compared with the
// declared ones; only the declared counts are charged before it runs.)
#pragma once

#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>

#include "common/status.h"
#include "scene/gltf_document.h"
#include "scene/import_budget.h"

namespace luxel::scene {

inline constexpr const char* kDracoExtension = "KHR_draco_mesh_compression";
inline constexpr const char* kMeshoptExtension = "EXT_meshopt_compression";

// Whether the JSON uses either extension on a primitive, bufferView or
// buffer (not merely lists it).
bool uses_compressed_geometry(const nlohmann::json& doc);

// Rewrites `doc` into the equivalent plain document. `max_elements` bounds
// the decoded elements over the document: vertices of every Draco primitive
// (once per decoded attribute), indices, and meshopt bufferView elements
// (ImportOptions::max_accessor_elements for the importer). With `budget`, the
// decoded bytes are reserved in it from the declared counts before decoding
// (scene/import_budget.h) and its deadline is checked per view / primitive.
Status decompress_geometry(GltfDocument* doc,
                           uint64_t max_elements = std::numeric_limits<uint64_t>::max(),
                           detail::ImportBudget* budget = nullptr);

}  // namespace luxel::scene
