// Internal to the settings schema's table (schema_table_*.cpp): the
// accessors that bind a setting to its BakeSettings member, and the
// predicates and descriptions the entries share.
#pragma once

#include <string>
#include <type_traits>
#include <vector>

#include "common/choices.h"
#include "common/status.h"
#include "settings/bake_settings.h"
#include "settings/settings_schema.h"

namespace luxel::pipeline::schema {

using Type = SettingType;
using Scope = SettingScope;

// Accessors binding a setting to a BakeSettings member. Values reach a
// setter only after check_setting, so the casts stay in range.
#define LUXEL_NUMBER(member)                                                       \
  .get = [](const BakeSettings& s) { return SettingValue::of(double(s.member)); }, \
  .set = [](BakeSettings& s, const SettingValue& v) {                              \
    s.member = static_cast<std::remove_cvref_t<decltype(s.member)>>(v.number);     \
  }
#define LUXEL_BOOL(member)                                                             \
  .get = [](const BakeSettings& s) { return SettingValue::of(s.member ? 1.0 : 0.0); }, \
  .set = [](BakeSettings& s, const SettingValue& v) { s.member = v.number != 0; }
#define LUXEL_VEC3(member)                                                     \
  .get = [](const BakeSettings& s) { return SettingValue::of_vec(s.member); }, \
  .set = [](BakeSettings& s, const SettingValue& v) { s.member = v.vec; }
#define LUXEL_TEXT(member)                                                      \
  .get = [](const BakeSettings& s) { return SettingValue::of_text(s.member); }, \
  .set = [](BakeSettings& s, const SettingValue& v) { s.member = v.text; }
// A member of a choice enum (common/choices.h); .choices = choice_list<E>()
// gives its names. check_setting admits only those, hence the CHECK.
#define LUXEL_CHOICE(member)                                                                 \
  .get = [](const BakeSettings& s) { return SettingValue::of_text(choice_name(s.member)); }, \
  .set = [](BakeSettings& s, const SettingValue& v) {                                        \
    const auto c = parse_choice<std::remove_cvref_t<decltype(s.member)>>(v.text);            \
    LUXEL_CHECK_MSG(c.has_value(), "a choice reaches its setter checked");                   \
    s.member = *c;                                                                           \
  }

inline constexpr double kU32Max = 4294967295.0;
inline constexpr double kI32Max = 2147483647.0;

using SkyKind = SkySettings::Kind;

inline bool has_sky(const BakeSettings& s) {
  return s.lights.sky.kind != SkyKind::kNone;
}
inline bool has_equirect_sky(const BakeSettings& s) {
  return s.lights.sky.kind == SkyKind::kEquirect;
}
inline bool has_sun(const BakeSettings& s) {
  return s.lights.sun.enabled;
}
inline bool has_encodings(const BakeSettings& s) {
  return !s.encodings.names.empty();
}
inline bool has_probes(const BakeSettings& s) {
  return !s.probes.empty();
}

inline std::string describe_sky(const BakeSettings& s) {
  const SkySettings& sky = s.lights.sky;
  switch (sky.kind) {
    case SkyKind::kConstant:
      return strprintf("constant %g,%g,%g x %g", sky.color.x, sky.color.y, sky.color.z,
                       sky.intensity);
    case SkyKind::kEquirect:
      return strprintf("equirect %s x %g rot %g", sky.equirect_path.c_str(), sky.intensity,
                       sky.rotation_degrees);
    case SkyKind::kNone:
      break;
  }
  return choice_name(sky.kind);
}

inline std::string describe_sun(const BakeSettings& s) {
  const SunSettings& sun = s.lights.sun;
  return strprintf("dir %g,%g,%g E %g radius %g deg", sun.direction.x, sun.direction.y,
                   sun.direction.z, sun.illuminance, sun.angular_radius_degrees);
}

// The table in its order (the CLI's help, `luxel settings` and the API
// follow it): stopping rules, lightmap size and light transport; then sky
// and sun, encodings, ablations, reports and outputs, probes, the daemon's
// job.
void add_bake_settings(std::vector<Setting>& t);
void add_scene_and_output_settings(std::vector<Setting>& t);

}  // namespace luxel::pipeline::schema
