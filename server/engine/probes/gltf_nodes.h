// Probe positions tagged in the scene file: glTF nodes whose extras carry
// "luxelProbe": true (any node, with or without a mesh), at the origin of
// the node's world transform (translation/rotation/scale or matrix,
// composed down the hierarchy of the default scene, glTF 2.0 §3.5.2-3.5.3).
// The placement's `nodes` mode bakes probes there (placement.h).
#pragma once

#include <string>

#include "common/status.h"

namespace luxel::probes {

// The probe positions of a .gltf (JSON) or .glb file's bytes, as the JSON
// list that placement's file_contents takes ("[[x,y,z], ...]").
// INVALID_ARGUMENT for a malformed file or when no node is tagged.
Result<std::string> probe_nodes_json(const std::string& gltf_or_glb);

}  // namespace luxel::probes
