// Front end of the importer: bytes (.gltf JSON or .glb) -> tinygltf::Model.
//
// tinygltf 2.7 trusts its input in places (GLB chunk bounds, image buffer
// views, deeply nested extras recurse). Everything it would trust is checked
// here first, with errors that name the buffer / image / uri at fault and the
// status codes the service maps to gRPC: kDataLoss for truncated data,
// kNotFound for missing external files, kInvalidArgument otherwise.
#pragma once

#include <string>
#include <string_view>

#include "common/status.h"
#include "scene/import_budget.h"
#include "scene/tinygltf_config.h"

namespace luxel::scene::detail {

// Deepest JSON nesting accepted (glTF itself needs about 8; extras may add a
// few). Bounds the recursion of tinygltf's JSON-to-Value conversion.
inline constexpr int kMaxJsonDepth = 64;

// Parses the document. External URIs resolve against base_dir; an empty
// base_dir forbids external files. URIs must be relative and stay inside
// base_dir (no "..", no absolute paths): uploaded scenes must not read other
// files of the server. Compressed geometry (KHR_draco_mesh_compression,
// EXT_meshopt_compression) is decoded first (scene/gltf_decompress.h), at
// most budget->elements_left elements and the bytes `budget` allows; tinygltf
// sees the plain file.
Status load_model(std::string_view bytes, const std::string& base_dir, const std::string& name,
                  ImportBudget* budget, tinygltf::Model* model);

}  // namespace luxel::scene::detail
