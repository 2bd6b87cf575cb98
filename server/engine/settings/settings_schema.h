// The bake settings schema: the one description of every setting a bake
// takes. Per setting: its name (the field path used in errors, in the proto
// and by the Python client: "sky.color" is reported as "settings.sky.color"),
// type, default, range, units, help text, CLI flag, where it is available
// (everywhere, `luxel bake --local` only, or the daemon API only), and the
// accessors that bind it to a BakeSettings field.
//
// Everything else follows from this table: validate_settings() checks it,
// the CLI builds its flags and help from it, the service translates
// luxel.v1.BakeSettings with it (proto field = setting name), `luxel settings
// --json` describes it for the Python client, and docs/api.md tabulates it.
// BakeSettings::describe(), the settings fingerprint, is built from it too
// (the describe fields of Setting). Adding a setting is one entry here (plus
// the proto field when the API carries it); a unit test fails when the
// schema and the proto disagree.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "common/math.h"
#include "common/status.h"

namespace luxel::pipeline {

struct BakeSettings;

enum class SettingType {
  kInt,         // an integer number (stored as double in SettingValue)
  kFloat,       // a real number
  kBool,        // on/off; a CLI flag inverts the default
  kChoice,      // one name of `choices` (a proto enum)
  kChoiceList,  // names of `choices`, each at most once (a repeated proto enum)
  kVec3,        // three reals, "X,Y,Z" on the command line (a repeated float of 3)
  kText,        // free text (a file name, an id)
};

// Where a setting can be given.
enum class SettingScope {
  kEverywhere,  // `luxel bake --local`, the daemon API (and so `luxel bake`)
  kLocalOnly,   // only in-process: the API has no field for it
  kApiOnly,     // only the daemon: how the job is run and delivered
};

// Whether a setting has an entry in BakeSettings::describe(), the settings
// fingerprint: manifests list it, checkpoints and shard merges compare its
// hash (settings/fingerprint.h), so an entry's key and text must not change
// once bakes have been checkpointed with it.
enum class Described {
  kAlways,         // "key=value" whenever the setting is active
  kUnlessDefault,  // only when the value is not the default: a setting added after
                   // checkpoints existed leaves the fingerprints of bakes that do
                   // not use it as they were
  kNever,          // not part of the result (the daemon's job, reports), folded into
                   // another setting's entry (describe_text), or never listed
                   // (sun.color, directional_angular_radius_degrees: their
                   // entries say so)
};

// What a proto3 field left at zero (or empty) means: scalars without
// explicit presence cannot tell "unset" from 0.
enum class ApiZero {
  kDefault,  // the setting's default ("0 means 2")
  kValue,    // the value 0 itself ("0 = no sample rule"); the API default is then 0
};

struct SettingValue {
  double number = 0;              // kInt, kFloat, kBool (0 or 1)
  std::string text;               // kChoice (the choice's name), kText
  std::vector<std::string> list;  // kChoiceList
  Vec3 vec{};                     // kVec3

  static SettingValue of(double x) { return {x, {}, {}, {}}; }
  static SettingValue of_text(std::string t) { return {0, std::move(t), {}, {}}; }
  static SettingValue of_list(std::vector<std::string> l) { return {0, {}, std::move(l), {}}; }
  static SettingValue of_vec(Vec3 v) { return {0, {}, {}, v}; }
};

inline constexpr double kUnbounded = std::numeric_limits<double>::infinity();

struct Setting {
  const char* name;  // field path below "settings." (proto field path too)
  SettingType type;
  const char* units;    // "" when dimensionless
  const char* help;     // one line; the CLI, docs and proto comments say the same
  const char* flag;     // CLI option ("--bounces"); nullptr: no option of its own
  const char* metavar;  // CLI value name ("N"); nullptr for kBool
  SettingValue default_value;
  // Range of a number, or of each component of a kVec3; for kChoiceList,
  // max is the most entries. Bounds are inclusive unless *_open.
  double min = -kUnbounded;
  double max = kUnbounded;
  bool min_open = false;
  bool max_open = false;
  // Values in (0, raise_to) are raised to raise_to (rate limits); 0: none.
  double raise_to = 0;
  bool nonzero = false;              // kVec3: must not be (0, 0, 0)
  bool zero_is_auto = false;         // kInt: 0 is accepted besides [min, max] (the engine picks)
  std::vector<const char*> choices;  // kChoice, kChoiceList
  std::vector<const char*> local_choices;  // choices the API cannot carry
  SettingScope scope = SettingScope::kEverywhere;
  ApiZero api_zero = ApiZero::kDefault;
  const char* api_note = nullptr;  // what the API does differently, for docs
  // What giving the setting's CLI flag also sets (--sky: a constant sky).
  void (*implies)(BakeSettings&) = nullptr;
  SettingValue (*get)(const BakeSettings&) = nullptr;
  void (*set)(BakeSettings&, const SettingValue&) = nullptr;
  // Whether the setting takes part in the bake (e.g. sky.color only with a
  // sky): inactive settings are neither validated nor sent to the daemon.
  bool (*active)(const BakeSettings&) = nullptr;

  // The setting's entry in BakeSettings::describe(). By default it is
  // "name=value" while the setting is active: integers in decimal (0 of a
  // zero_is_auto setting as "auto"), reals as %g, switches on/off, choices
  // and text as they are, lists comma-separated, triples "x,y,z". The
  // fields below record where an entry differs from that.
  Described described = Described::kAlways;
  const char* describe_key = nullptr;                    // the key, when not the name
  bool (*describe_when)(const BakeSettings&) = nullptr;  // and only when this holds
  // The entry's text, when it is not the value's own: settings folded into
  // one entry ("adaptive=on,min=8"), or a value written in other words.
  std::string (*describe_text)(const BakeSettings&) = nullptr;
  // The text's 64-bit FNV-1a, 16 hex digits, instead of the text itself
  // (a long value: the JSON list of probe positions; the offset basis is
  // describe()'s own, bake_settings.cpp).
  bool describe_fnv1a = false;

  bool is_active(const BakeSettings& s) const { return !active || active(s); }
  bool in_api() const { return scope != SettingScope::kLocalOnly; }
  bool in_local() const { return scope != SettingScope::kApiOnly; }
};

// Every setting, in help order.
const std::vector<Setting>& settings_schema();
// nullptr when there is no such setting.
const Setting* find_setting(const std::string& name);

// The schema's defaults: what a bake does when nothing is given. (A
// value-initialised BakeSettings differs only in the lightmap size: its
// resolution is 0.)
BakeSettings default_settings();

// The rule of one setting: INVALID_ARGUMENT "settings.<name>: <why>" when
// `v` is out of range, not finite, not one of the choices, ...
Status check_setting(const Setting& setting, const SettingValue& v);
// check_setting, then stores the value (raised to raise_to) and what the
// setting implies. The CLI and the service set every setting through this.
Status apply_setting(BakeSettings& s, const Setting& setting, SettingValue v);

// Text forms used by the CLI and docs: "4", "0.27", "1,1,1", "sh2,sg12", "png".
std::string format_setting_value(const Setting& setting, const SettingValue& v);
// Parses the command-line text of a setting (no range check).
Result<SettingValue> parse_setting_value(const Setting& setting, const std::string& text);
// "[0, 64]", ">= 0", "(0, 90)", "box | gaussian", ... for docs and help.
std::string describe_range(const Setting& setting);

// The text of `v` in BakeSettings::describe() (the default rule above, no
// describe_text or hash).
std::string describe_setting_value(const Setting& setting, const SettingValue& v);
// Whether `a` and `b` are the same value of `setting` (Described::kUnlessDefault).
bool same_setting_value(const Setting& setting, const SettingValue& a, const SettingValue& b);

// The schema as JSON (name, type, units, help, flag, default, range,
// choices, scope, api_zero): `luxel settings --json`, read by the Python
// client.
std::string settings_schema_json();

}  // namespace luxel::pipeline
