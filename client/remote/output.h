// How remote commands print: JSON lines for scripts (--json) and short
// human-readable blocks and tables otherwise.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "luxel/v1/luxel.pb.h"
#include "progress_bar.h"

namespace luxel::cli::remote {

// A message as JSON with the .proto field names, every field present (proto3
// JSON mapping: enums are names, 64-bit integers are strings).
nlohmann::json to_json(const google::protobuf::Message& message);

// Prints one JSON object on one line of stdout and flushes.
void print_json_line(const nlohmann::json& object);

// "RUNNING" for BAKE_STATE_RUNNING.
std::string state_name(luxel::v1::BakeState state);
// Accepts "running", "RUNNING" or "BAKE_STATE_RUNNING".
bool parse_state(const std::string& text, luxel::v1::BakeState& state);
bool is_terminal(luxel::v1::BakeState state);

ProgressView progress_view(const luxel::v1::BakeProgress& p);

void print_scene_info(const luxel::v1::SceneInfo& scene);
void print_bake_info(const luxel::v1::BakeInfo& bake);
void print_scene_table(const luxel::v1::ListScenesResponse& scenes);
void print_bake_table(const luxel::v1::ListBakesResponse& bakes);

}  // namespace luxel::cli::remote
