// The fingerprint of a bake: a hash of the scene id and every setting that
// shapes the result. A checkpoint stores it and only resumes the bake it was
// written for (shards/checkpoint.h); shards of one bake share it, so their
// accumulators merge (shards/shard_merge.h).
#pragma once

#include <string>

#include "settings/bake_settings.h"

namespace luxel::pipeline {

std::string bake_fingerprint(const std::string& scene_id, const BakeSettings& settings);

}  // namespace luxel::pipeline
