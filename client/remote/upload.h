// Scene upload: the UploadScene client stream (header, then the main file and
// each external resource in 64 KiB chunks), and "upload unless the daemon
// already has it" for `luxel bake`.
#pragma once

#include <string>

#include "api/scene_files.h"
#include "remote/connection.h"

namespace luxel::cli::remote {

inline constexpr size_t kUploadChunkBytes = 64 * 1024;

// Streams `files` to the daemon and returns what it made of them.
grpc::Status upload_scene(Connection& conn, const SceneFiles& files, const std::string& name,
                          luxel::v1::SceneInfo& info);

// Asks GetScene for the scene id of `files` (main file and resources) first and uploads only when
// the daemon answers NOT_FOUND. `uploaded` says whether bytes were sent.
grpc::Status ensure_scene(Connection& conn, const SceneFiles& files, const std::string& name,
                          luxel::v1::SceneInfo& info, bool& uploaded);

}  // namespace luxel::cli::remote
