#include "settings/fingerprint.h"

#include "common/hash.h"

namespace luxel::pipeline {

std::string bake_fingerprint(const std::string& scene_id, const pipeline::BakeSettings& settings) {
  Hasher h;
  h.add(scene_id);
  // describe() already leaves out what shapes reports, not the lightmap
  // (progress_interval_s and the daemon's job settings: Described::kNever).
  for (const auto& [key, value] : settings.describe()) {
    // Shards of one bake share the fingerprint (their states merge,
    // shards/shard_merge.h); the checkpoint records the shard itself.
    if (key == "shard") continue;
    h.add(key).add("=").add(value).add("\n");
  }
  return h.hex();
}

}  // namespace luxel::pipeline
