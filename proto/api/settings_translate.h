// luxel.v1.BakeSettings <-> pipeline::BakeSettings, driven by the settings
// schema (settings/settings_schema.h): every API setting's proto field has
// the setting's name as its path ("sky.color" is BakeSettings.sky.color), so
// one table-driven loop translates them all through protobuf reflection.
// Proto zeros are resolved as the schema says (ApiZero), the daemon's limits
// are applied, and every error is INVALID_ARGUMENT naming the field
// ("settings.sky.color: expected 3 values, got 1").
#pragma once

#include <string>

#include "bake/bake.h"
#include "common/status.h"
#include "luxel/v1/luxel.pb.h"
#include "settings/bake_settings.h"
#include "settings/settings_schema.h"

namespace luxel::service {

struct SettingsLimits {
  int max_resolution = 4096;  // --max-resolution: lightmap side in texels
};

// Translates and validates, once, at SubmitBake: each setting's schema rule,
// then pipeline::validate_settings' rules between settings, against the
// daemon's limits.
Result<pipeline::BakeSettings> to_engine_settings(const v1::BakeSettings& in,
                                                  const SettingsLimits& limits);

// Translation only, for settings to_engine_settings accepted before (a stored
// bake about to run): no validation.
pipeline::BakeSettings stored_engine_settings(const v1::BakeSettings& in,
                                              const SettingsLimits& limits);

// The API form of engine settings (what `luxel bake` submits): every active
// setting the API carries. INVALID_ARGUMENT naming the field for a value the
// API cannot express (0 where the API reads 0 as another default, a
// local-only choice).
Result<v1::BakeSettings> to_proto_settings(const pipeline::BakeSettings& s);

// The proto field of a setting path ("sun.direction"), nullptr if none.
const google::protobuf::FieldDescriptor* proto_field(const std::string& path);
// The proto enum value name of a schema choice: ("constant", Sky.Kind) -> "KIND_CONSTANT".
std::string proto_enum_name(const google::protobuf::EnumDescriptor* e, const std::string& choice);

v1::SnapshotFormat to_proto(pipeline::SnapshotFormat f);
v1::BakeProgress to_proto(const pipeline::BakeProgress& p);

}  // namespace luxel::service
