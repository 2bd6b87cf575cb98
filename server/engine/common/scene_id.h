// The scene id: how the daemon stores an uploaded scene and how the CLI
// names the scene it is about to upload (the rule in luxel.proto's header
// comment). Both sides call this one function, so an already-stored check on
// the client and the daemon's content addressing cannot drift apart.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace luxel {

// One external resource of a .gltf: the uri as written in the file (not
// percent-decoded), its size in bytes and its lowercase hex sha256.
struct SceneIdResource {
  std::string uri;
  uint64_t size = 0;
  std::string sha256;
};

// The main file's sha256 when there are no external resources; otherwise the
// sha256 (lowercase hex) of "luxel-scene-v1\n" + "<main sha256>\n" + one line
// "<uri>\t<size>\t<sha256>\n" per resource, sorted by uri (byte order). So a
// changed .bin beside an unchanged .gltf is a different scene. The order of
// `resources` does not matter.
std::string scene_id(const std::string& main_sha256, std::vector<SceneIdResource> resources);

}  // namespace luxel
