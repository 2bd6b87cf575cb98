// The files an upload sends: the main .gltf/.glb and, for a .gltf, every
// external buffer and image it references (buffers[].uri and images[].uri
// that are not data: URIs), each with its size and sha256.
#pragma once

#include <grpcpp/support/status.h>

#include <cstdint>
#include <string>
#include <vector>

#include "luxel/v1/luxel.pb.h"

namespace luxel::cli::remote {

struct SceneFile {
  std::string uri;     // as written in the .gltf (empty for the main file)
  std::string path;    // where it is on this machine
  uint64_t size = 0;   // bytes
  std::string sha256;  // lowercase hex
};

struct SceneFiles {
  SceneFile main;
  luxel::v1::SceneFormat format = luxel::v1::SCENE_FORMAT_UNSPECIFIED;
  std::vector<SceneFile> resources;  // in upload order, each uri once
};

// Reads the scene at `path`, finds its external resources and hashes all of
// them. Errors name the file or uri: INVALID_ARGUMENT (not .gltf/.glb, bad
// JSON, a uri that is not a relative file), NOT_FOUND (a missing resource).
grpc::Status collect_scene_files(const std::string& path, SceneFiles& out);

// The id the daemon gives these files: common/scene_id.h, the function the
// daemon's SceneStore uses too.
std::string scene_id(const SceneFiles& files);

// The upload header for `files` (display name `name`, or the file name).
luxel::v1::SceneUploadHeader upload_header(const SceneFiles& files, const std::string& name);

}  // namespace luxel::cli::remote
