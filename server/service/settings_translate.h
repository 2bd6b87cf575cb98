// luxel.v1 messages <-> engine structs. Proto defaults ("0 means ...") are
// resolved here, the daemon's limits are applied, and every error is
// INVALID_ARGUMENT naming the field ("settings.sky.color: expected 3 values").
#pragma once

#include <string>

#include "common/status.h"
#include "luxel/v1/luxel.pb.h"
#include "pipeline/bake.h"
#include "pipeline/bake_settings.h"

namespace luxel::service {

struct SettingsLimits {
  int max_resolution = 4096;  // --max-resolution: lightmap side in texels
};

// What the daemon needs besides the engine settings.
struct ServiceBakeOptions {
  double snapshot_interval_s = 5;
  v1::SnapshotFormat snapshot_format = v1::SNAPSHOT_FORMAT_PNG;
  int snapshot_max_side = 512;
};

// Translates and validates (pipeline::validate_settings plus the daemon's checks).
Result<pipeline::BakeSettings> to_engine_settings(const v1::BakeSettings& in,
                                                  const SettingsLimits& limits,
                                                  ServiceBakeOptions* options = nullptr);

v1::BakeProgress to_proto(const pipeline::BakeProgress& p);

// A hash of the scene id and every result-shaping setting, stored in
// checkpoints: a checkpoint only resumes the bake it was written for.
std::string bake_fingerprint(const std::string& scene_id, const pipeline::BakeSettings& settings);

}  // namespace luxel::service
