// Structured logs: one line per event on stderr, key=value pairs, so a log
// shipper or grep can follow a bake or a scene by its id:
//   ts=2024-05-01T12:00:00.123Z event=bake_started bake=9f.. scene=3a..
// Values with spaces, quotes or '=' are quoted with "..." (quotes escaped).
#pragma once

#include <initializer_list>
#include <string>
#include <utility>

namespace luxel::service {

using LogField = std::pair<const char*, std::string>;

// Writes one line atomically with respect to other log_event calls.
void log_event(const char* event, std::initializer_list<LogField> fields = {});

}  // namespace luxel::service
