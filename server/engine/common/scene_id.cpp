#include "common/scene_id.h"

#include <algorithm>

#include "common/sha256.h"

namespace luxel {

std::string scene_id(const std::string& main_sha256, std::vector<SceneIdResource> resources) {
  if (resources.empty()) return main_sha256;
  // std::string's operator< compares bytes as unsigned char: byte order.
  std::sort(resources.begin(), resources.end(),
            [](const SceneIdResource& a, const SceneIdResource& b) { return a.uri < b.uri; });
  Sha256 manifest;
  manifest.update("luxel-scene-v1\n");
  manifest.update(main_sha256 + "\n");
  for (const SceneIdResource& r : resources)
    manifest.update(r.uri + "\t" + std::to_string(r.size) + "\t" + r.sha256 + "\n");
  return manifest.hex_digest();
}

}  // namespace luxel
