// The settings schema and validate_settings: one test per rule family, the
// sun radius (once two disagreeing ranges), and that the schema's defaults are
// the ones BakeSettings' initialisers and the rest of the engine assume.
#include "settings/settings_schema.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "settings/bake_settings.h"

namespace luxel::pipeline {
namespace {

std::string error_of(const Status& st) {
  return st.is_ok() ? "ok" : st.message();
}

// Sets one setting from its command-line text and validates, as the CLI does.
std::string cli_error(const std::string& name, const std::string& text,
                      BakeSettings s = default_settings()) {
  const Setting* st = find_setting(name);
  EXPECT_NE(st, nullptr) << name;
  if (!st) return "no setting";
  auto v = parse_setting_value(*st, text);
  if (!v) return v.status().message();
  if (Status a = apply_setting(s, *st, v.value()); !a.is_ok()) return a.message();
  if (st->implies) st->implies(s);
  return error_of(validate_settings(s));
}

TEST(SettingsSchema, NamesAreUniqueAndEveryEntryIsComplete) {
  std::set<std::string> names, flags;
  for (const Setting& st : settings_schema()) {
    EXPECT_TRUE(names.insert(st.name).second) << st.name;
    if (st.flag) EXPECT_TRUE(flags.insert(st.flag).second) << st.flag;
    EXPECT_NE(st.get, nullptr) << st.name;
    EXPECT_NE(st.set, nullptr) << st.name;
    EXPECT_GT(std::string(st.help).size(), 10u) << st.name;
    // Every default obeys its own rule.
    EXPECT_TRUE(check_setting(st, st.default_value).is_ok())
        << st.name << ": " << error_of(check_setting(st, st.default_value));
  }
}

TEST(SettingsSchema, DefaultsValidateAndRoundTrip) {
  const BakeSettings d = default_settings();
  EXPECT_TRUE(validate_settings(d).is_ok()) << error_of(validate_settings(d));
  for (const Setting& st : settings_schema())
    EXPECT_EQ(format_setting_value(st, st.get(d)), format_setting_value(st, st.default_value))
        << st.name;
}

// BakeSettings' own initialisers (read by code that builds settings by hand)
// agree with the schema everywhere but in the lightmap size, which a
// value-initialised BakeSettings leaves to the caller (no size, pages up to
// the engine's limit); the schema's default is a texel density.
TEST(SettingsSchema, StructInitialisersAgreeWithTheSchema) {
  const BakeSettings plain;
  for (const Setting& st : settings_schema()) {
    const std::string name = st.name;
    if (name == "resolution" || name == "texel_density" || name == "max_resolution") continue;
    EXPECT_EQ(format_setting_value(st, st.get(plain)), format_setting_value(st, st.default_value))
        << st.name;
  }
  EXPECT_EQ(plain.atlas.resolution, 0);
  EXPECT_EQ(plain.atlas.texel_density, 0);
  EXPECT_EQ(plain.atlas.max_resolution, atlas::kResolutionLimit);
  const BakeSettings d = default_settings();
  EXPECT_EQ(d.atlas.resolution, 0);
  EXPECT_EQ(d.atlas.texel_density, 40);
  EXPECT_EQ(d.atlas.max_resolution, 1024);
}

TEST(SettingsValidation, IntegerRanges) {
  EXPECT_EQ(cli_error("max_bounces", "99"), "settings.max_bounces: must be in [0, 64], got 99");
  EXPECT_EQ(cli_error("max_bounces", "-1"), "settings.max_bounces: must be in [0, 64], got -1");
  EXPECT_EQ(cli_error("max_bounces", "2.5"),
            "settings.max_bounces: must be a whole number, got 2.5");
  EXPECT_EQ(cli_error("max_bounces", "64"), "ok");
  EXPECT_EQ(cli_error("paths_per_iteration", "5"),
            "settings.paths_per_iteration: must be 0 (auto) or in [1024, 67108864], got 5");
  EXPECT_EQ(cli_error("paths_per_iteration", "0"), "ok");  // auto: the device's batch
  EXPECT_EQ(cli_error("paths_per_iteration", "1023"),
            "settings.paths_per_iteration: must be 0 (auto) or in [1024, 67108864], got 1023");
  EXPECT_EQ(cli_error("samples_per_texel", "-3"),
            "settings.samples_per_texel: must be in [0, 4294967295], got -3");
  EXPECT_EQ(cli_error("rr_depth", "0"), "settings.rr_depth: must be in [1, 64], got 0");
  EXPECT_EQ(cli_error("dilation_texels", "65"),
            "settings.dilation_texels: must be in [0, 64], got 65");
  EXPECT_EQ(cli_error("max_bounces", "lots"),
            "settings.max_bounces: expected a number, got 'lots'");
}

TEST(SettingsValidation, RealRangesAndFiniteness) {
  EXPECT_EQ(cli_error("time_budget_s", "-1"), "settings.time_budget_s: must be >= 0, got -1");
  EXPECT_EQ(cli_error("time_budget_s", "inf"),
            "settings.time_budget_s: must be a finite number, got inf");
  EXPECT_EQ(cli_error("target_error", "nan"),
            "settings.target_error: must be a finite number, got nan");
  EXPECT_EQ(cli_error("sg_sharpness", "0.1"),
            "settings.sg_sharpness: must be in [0.25, 256], got 0.1");
  EXPECT_EQ(cli_error("acceleration", "100"),
            "settings.acceleration: must be in [0.5, 8], got 100");
  EXPECT_EQ(cli_error("progress_interval_s", "0"),
            "settings.progress_interval_s: must be > 0, got 0");
  EXPECT_EQ(cli_error("clamp_luminance", "-2"), "settings.clamp_luminance: must be >= 0, got -2");
}

// The sun radius had two rules ([0, 45] in the service, [0, 90) in the light
// builder); the schema's [0, 90) is now the only one, for the sun and for the
// scene's directional lights alike.
TEST(SettingsValidation, SunRadiusHasOneRule) {
  BakeSettings with_sun = default_settings();
  with_sun.lights.sun.enabled = true;
  EXPECT_EQ(cli_error("sun.angular_radius_degrees", "90", with_sun),
            "settings.sun.angular_radius_degrees: must be in [0, 90), got 90");
  EXPECT_EQ(cli_error("sun.angular_radius_degrees", "-0.5", with_sun),
            "settings.sun.angular_radius_degrees: must be in [0, 90), got -0.5");
  EXPECT_EQ(cli_error("sun.angular_radius_degrees", "60", with_sun), "ok");
  EXPECT_EQ(cli_error("sun.angular_radius_degrees", "0", with_sun), "ok");
  EXPECT_EQ(cli_error("directional_angular_radius_degrees", "95"),
            "settings.directional_angular_radius_degrees: must be in [0, 90), got 95");
  const Setting* radius = find_setting("sun.angular_radius_degrees");
  EXPECT_EQ(radius->max, kMaxAngularRadiusDegrees);
  EXPECT_TRUE(radius->max_open);
  // A value set in code is checked by validate_settings with the same words.
  with_sun.lights.sun.angular_radius_degrees = 45.5f;
  EXPECT_TRUE(validate_settings(with_sun).is_ok());
  with_sun.lights.sun.angular_radius_degrees = 91;
  EXPECT_EQ(error_of(validate_settings(with_sun)),
            "settings.sun.angular_radius_degrees: must be in [0, 90), got 91");
}

TEST(SettingsValidation, Choices) {
  EXPECT_EQ(cli_error("filter", "bilinear"),
            "settings.filter: 'bilinear' is not one of box, gaussian");
  EXPECT_EQ(cli_error("solver", "magic"),
            "settings.solver: 'magic' is not one of auto, projection, progressive, progressive-nn");
  EXPECT_EQ(cli_error("target_metric", "psnr"),
            "settings.target_metric: 'psnr' is not one of estimate, rmse, relmse");
  EXPECT_EQ(cli_error("filter", "gaussian"), "ok");
}

// The choices and their order are an interface (the CLI help, `luxel
// settings --json`, the proto translation and docs list them), so they are
// written out here; each name reaches its enum and comes back.
TEST(SettingsSchema, ChoicesKeepTheirNamesAndOrderAndRoundTrip) {
  const std::map<std::string, std::vector<std::string>> expected = {
      {"target_metric", {"estimate", "rmse", "relmse"}},
      {"filter", {"box", "gaussian"}},
      {"direct", {"auto", "analytic", "sampled"}},
      {"intersector", {"auto", "embree", "opencl"}},
      {"uv", {"auto", "generate", "existing"}},
      {"sky.kind", {"none", "constant", "equirect"}},
      {"solver", {"auto", "projection", "progressive", "progressive-nn"}},
      {"denoise", {"off", "atrous", "oidn", "auto"}},
      {"snapshot_format", {"png", "exr", "none"}},
  };
  std::map<std::string, std::vector<std::string>> got;
  for (const Setting& st : settings_schema()) {
    if (st.type != SettingType::kChoice) continue;
    got[st.name] = {st.choices.begin(), st.choices.end()};
    for (const char* c : st.choices) {
      BakeSettings s = default_settings();
      ASSERT_TRUE(apply_setting(s, st, SettingValue::of_text(c)).is_ok()) << st.name << " " << c;
      EXPECT_EQ(st.get(s).text, c) << st.name;
    }
  }
  EXPECT_EQ(got, expected);
}

TEST(SettingsValidation, ChoiceLists) {
  EXPECT_EQ(cli_error("encodings", "irradiance,sh2,sg12-hemi"), "ok");
  EXPECT_EQ(cli_error("encodings", "sh9").substr(0, 45),
            "settings.encodings: 'sh9' is not one of irrad");
  EXPECT_EQ(cli_error("encodings", "sh2,sh2"), "settings.encodings: 'sh2' is listed twice");
  EXPECT_EQ(
      cli_error("encodings", "sh1,sh2,sg6,sg9,sg12,sg6-hemi,sg9-hemi,sg12-hemi,ambient-dice9"),
      "settings.encodings: at most 8 at once, got 9");
  BakeSettings s = default_settings();
  ASSERT_TRUE(
      apply_setting(s, *find_setting("encodings"), SettingValue::of_list({"irradiance", "sh2"}))
          .is_ok());
  EXPECT_EQ(s.encodings.names, std::vector<std::string>{"sh2"});  // irradiance is implicit
}

TEST(SettingsValidation, Vectors) {
  EXPECT_EQ(cli_error("sky.color", "1,2"),
            "settings.sky.color: expected three comma-separated numbers, got '1,2'");
  EXPECT_EQ(cli_error("sky.color", "1,-2,3"),
            "settings.sky.color: each value must be >= 0, got (1, -2, 3)");
  EXPECT_EQ(cli_error("sun.direction", "0,0,0"), "settings.sun.direction: must not be zero");
  EXPECT_EQ(cli_error("sun.direction", "0,nan,1"),
            "settings.sun.direction: values must be finite, got (0, nan, 1)");
  // Non-zero, but its squared length is no normal float (common/direction.h):
  // the bake could not normalize it on a thread that flushes denormals, so it
  // is refused here and not when the light table is built.
  const std::string not_normalizable =
      "settings.sun.direction: its squared length must be a normal single-precision float "
      "(about 1e-19 to 1e19 per component): it does not survive normalisation, got ";
  EXPECT_EQ(cli_error("sun.direction", "1e-45,0,0"), not_normalizable + "(1.4013e-45, 0, 0)");
  EXPECT_EQ(cli_error("sun.direction", "1e-19,0,0"), not_normalizable + "(1e-19, 0, 0)");
  EXPECT_EQ(cli_error("sun.direction", "3e38,3e38,0"), not_normalizable + "(3e+38, 3e+38, 0)");
  BakeSettings sun = default_settings();
  sun.lights.sun.enabled = true;
  sun.lights.sun.direction = {1e-45f, 0, 0};
  EXPECT_NE(error_of(validate_settings(sun)).find(not_normalizable), std::string::npos)
      << error_of(validate_settings(sun));
  EXPECT_EQ(cli_error("sun.direction", "2e-19,0,0"), "ok");
  BakeSettings s = default_settings();
  EXPECT_EQ(cli_error("sky.color", "0.2,0.3,0.5", s), "ok");
  // A setting of an absent light is not checked (the sun is off here).
  s.lights.sun.direction = {0, 0, 0};
  EXPECT_TRUE(validate_settings(s).is_ok());
}

TEST(SettingsValidation, RulesBetweenSettings) {
  BakeSettings s = default_settings();
  s.samples_per_texel = 0;
  EXPECT_EQ(error_of(validate_settings(s)),
            "settings.samples_per_texel: no stopping rule: set samples, a time budget or a "
            "target error");
  s = default_settings();
  s.target_metric = ErrorMetric::kRmse;
  EXPECT_EQ(error_of(validate_settings(s)),
            "settings.target_metric: 'rmse' needs a reference lightmap");
  s.job.reference_bake_id = "0123";
  EXPECT_TRUE(validate_settings(s).is_ok());
  s = default_settings();
  s.atlas.resolution_limit = 256;
  EXPECT_EQ(error_of(validate_settings(s, "the daemon's limit --max-resolution")),
            "settings.max_resolution: 1024 exceeds the daemon's limit --max-resolution=256");
  s.atlas.resolution = 512;
  EXPECT_EQ(error_of(validate_settings(s, "the daemon's limit --max-resolution")),
            "settings.resolution: 512 exceeds the daemon's limit --max-resolution=256");
  // A resolution is a page of its own: --max-resolution does not bound it.
  s = default_settings();
  EXPECT_EQ(cli_error("resolution", "4096", s), "ok");
  EXPECT_EQ(cli_error("resolution", "9000", s),
            "settings.resolution: 9000 exceeds the engine's largest lightmap side=8192");
  EXPECT_EQ(cli_error("max_resolution", "9000", s),
            "settings.max_resolution: must be in [1, 8192], got 9000");
  EXPECT_EQ(cli_error("texel_density", "0", s), "settings.texel_density: must be > 0, got 0");
  s.atlas.texel_density = 0;
  EXPECT_EQ(error_of(validate_settings(s)), "settings.texel_density: must be > 0, got 0");
}

TEST(SettingsSchema, RateLimitsAreRaisedNotRejected) {
  BakeSettings s = default_settings();
  ASSERT_TRUE(
      apply_setting(s, *find_setting("progress_interval_s"), SettingValue::of(0.01)).is_ok());
  EXPECT_EQ(s.progress_interval_s, 0.05);
}

TEST(SettingsSchema, FlagsImplyTheirLight) {
  BakeSettings s = default_settings();
  EXPECT_EQ(cli_error("sun.direction", "1,-1,0", s), "ok");
  const Setting* sun = find_setting("sun.direction");
  ASSERT_TRUE(apply_setting(s, *sun, parse_setting_value(*sun, "1,-1,0").value()).is_ok());
  sun->implies(s);
  EXPECT_TRUE(s.lights.sun.enabled);
  const Setting* sky = find_setting("sky.color");
  sky->implies(s);
  EXPECT_EQ(s.lights.sky.kind, SkySettings::Kind::kConstant);
}

TEST(SettingsSchema, JsonDescribesEverySetting) {
  const std::string json = settings_schema_json();
  for (const Setting& st : settings_schema())
    EXPECT_NE(json.find(std::string("\"name\": \"") + st.name + "\""), std::string::npos)
        << st.name;
}

}  // namespace
}  // namespace luxel::pipeline
