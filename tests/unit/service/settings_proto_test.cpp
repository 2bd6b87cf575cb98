// The API form of the settings schema: every schema setting the API carries
// has its proto field (and every proto field a schema setting), enum values
// match the schema's choices, translation round-trips, and a bad value is
// reported in the same words by the CLI path and by SubmitBake's translation.
#include <gtest/gtest.h>

#include <functional>
#include <set>

#include "api/settings_translate.h"
#include "settings/fingerprint.h"
#include "settings/settings_schema.h"

namespace luxel::service {
namespace {

namespace pb = google::protobuf;
using pipeline::Setting;
using pipeline::SettingType;

// Paths of every leaf field of BakeSettings ("sky.color").
void collect_fields(const pb::Descriptor* d, const std::string& prefix,
                    std::set<std::string>* out) {
  for (int i = 0; i < d->field_count(); ++i) {
    const pb::FieldDescriptor* f = d->field(i);
    if (f->message_type())
      collect_fields(f->message_type(), prefix + f->name() + ".", out);
    else
      out->insert(prefix + f->name());
  }
}

TEST(SettingsProto, EverySchemaSettingHasItsProtoFieldAndViceVersa) {
  std::set<std::string> fields;
  collect_fields(v1::BakeSettings::descriptor(), "", &fields);
  for (const Setting& st : pipeline::settings_schema()) {
    const pb::FieldDescriptor* f = proto_field(st.name);
    if (!st.in_api()) {
      EXPECT_EQ(f, nullptr) << st.name << " is local-only but the proto has it";
      continue;
    }
    ASSERT_NE(f, nullptr) << "schema setting " << st.name << " has no proto field";
    fields.erase(st.name);
    switch (st.type) {
      case SettingType::kInt:
      case SettingType::kFloat:
        EXPECT_FALSE(f->is_repeated()) << st.name;
        EXPECT_TRUE(f->cpp_type() != pb::FieldDescriptor::CPPTYPE_STRING &&
                    f->cpp_type() != pb::FieldDescriptor::CPPTYPE_ENUM)
            << st.name;
        break;
      case SettingType::kBool:
        EXPECT_EQ(f->type(), pb::FieldDescriptor::TYPE_BOOL) << st.name;
        break;
      case SettingType::kText:
        EXPECT_EQ(f->type(), pb::FieldDescriptor::TYPE_STRING) << st.name;
        break;
      case SettingType::kVec3:
        EXPECT_TRUE(f->is_repeated() && f->type() == pb::FieldDescriptor::TYPE_FLOAT) << st.name;
        break;
      case SettingType::kChoice:
      case SettingType::kChoiceList: {
        ASSERT_EQ(f->type(), pb::FieldDescriptor::TYPE_ENUM) << st.name;
        EXPECT_EQ(f->is_repeated(), st.type == SettingType::kChoiceList) << st.name;
        std::set<std::string> values;
        for (int i = 0; i < f->enum_type()->value_count(); ++i)
          if (f->enum_type()->value(i)->number() != 0 || st.type == SettingType::kChoice)
            values.insert(f->enum_type()->value(i)->name());
        for (const char* c : st.choices) {
          bool local = false;
          for (const char* l : st.local_choices) local |= std::string(c) == l;
          const std::string name = proto_enum_name(f->enum_type(), c);
          if (local) {
            EXPECT_EQ(values.count(name), 0u) << name;
            continue;
          }
          EXPECT_EQ(values.erase(name), 1u) << st.name << ": choice " << c << " has no " << name;
        }
        // What remains is the UNSPECIFIED value of a single choice (= the default).
        for (const auto& v : values)
          EXPECT_EQ(f->enum_type()->FindValueByName(v)->number(), 0) << st.name << ": " << v;
        break;
      }
    }
  }
  fields.erase("sky.kind");  // covered above; listed for clarity
  // Per-node placements: a list of structures outside the schema's scalar
  // settings, translated on their own (PlacementsRoundTripAndErrors).
  for (const char* f :
       {"placements.node", "placements.instance", "placements.scale_offset", "placements.page"})
    EXPECT_EQ(fields.erase(f), 1u) << f;
  for (const auto& f : fields)
    EXPECT_TRUE(f == "sky.kind") << "proto field settings." << f << " has no schema setting";
}

v1::BakeSettings base() {
  v1::BakeSettings p;
  p.set_samples_per_texel(16);
  return p;
}

std::string service_error(const v1::BakeSettings& p) {
  auto s = to_engine_settings(p, SettingsLimits{});
  return s ? "ok" : s.status().message();
}

// What the CLI prints after "luxel bake: " for one option.
std::string cli_error(const std::string& name, const std::string& text) {
  pipeline::BakeSettings s = pipeline::default_settings();
  const Setting* st = pipeline::find_setting(name);
  auto v = pipeline::parse_setting_value(*st, text);
  if (!v) return v.status().message();
  if (Status a = pipeline::apply_setting(s, *st, v.value()); !a.is_ok()) return a.message();
  if (st->implies) st->implies(s);
  Status st2 = pipeline::validate_settings(s);
  return st2.is_ok() ? "ok" : st2.message();
}

TEST(SettingsProto, ErrorsNameTheFieldIdenticallyInCliAndService) {
  struct Case {
    const char* setting;
    const char* cli;
    std::function<void(v1::BakeSettings&)> edit;
  };
  const std::vector<Case> cases = {
      {"max_bounces", "99", [](v1::BakeSettings& p) { p.set_max_bounces(99); }},
      {"paths_per_iteration", "5", [](v1::BakeSettings& p) { p.set_paths_per_iteration(5); }},
      {"time_budget_s", "-1", [](v1::BakeSettings& p) { p.set_time_budget_s(-1); }},
      {"sg_sharpness", "-2", [](v1::BakeSettings& p) { p.set_sg_sharpness(-2); }},
      {"acceleration", "100", [](v1::BakeSettings& p) { p.set_acceleration(100); }},
      {"dilation_texels", "65", [](v1::BakeSettings& p) { p.set_dilation_texels(65); }},
      {"sun.angular_radius_degrees", "95",
       [](v1::BakeSettings& p) {
         p.mutable_sun()->set_illuminance(1);
         p.mutable_sun()->set_angular_radius_degrees(95);
       }},
      {"sun.direction", "0,0,0",
       [](v1::BakeSettings& p) {
         p.mutable_sun()->set_illuminance(1);
         for (int i = 0; i < 3; ++i) p.mutable_sun()->add_direction(0);
       }},
      {"sky.color", "1,-1,1",
       [](v1::BakeSettings& p) {
         p.mutable_sky()->set_kind(v1::Sky::KIND_CONSTANT);
         for (float c : {1.f, -1.f, 1.f}) p.mutable_sky()->add_color(c);
       }},
      {"encodings", "sh2,sh2",
       [](v1::BakeSettings& p) {
         p.add_encodings(v1::ENCODING_SH2);
         p.add_encodings(v1::ENCODING_SH2);
       }},
      {"target_metric", "rmse",
       [](v1::BakeSettings& p) { p.set_target_metric(v1::TARGET_METRIC_RMSE); }},
  };
  for (const auto& c : cases) {
    v1::BakeSettings p = base();
    c.edit(p);
    const std::string service = service_error(p), cli = cli_error(c.setting, c.cli);
    EXPECT_EQ(service, cli) << c.setting;
    EXPECT_EQ(service.rfind(std::string("settings.") + c.setting + ": ", 0), 0u) << service;
  }
  // Errors only the API form can have name the field the same way.
  v1::BakeSettings p = base();
  p.mutable_sky()->set_kind(v1::Sky::KIND_CONSTANT);
  p.mutable_sky()->add_color(1);
  EXPECT_EQ(service_error(p), "settings.sky.color: expected 3 values, got 1");
  p = base();
  p.set_solver(static_cast<v1::Solver>(42));
  EXPECT_EQ(service_error(p), "settings.solver: unknown value 42 of Solver");
  p = base();
  p.set_resolution(5000);
  EXPECT_EQ(service_error(p),
            "settings.resolution: 5000 exceeds the daemon's limit --max-resolution=4096");
}

TEST(SettingsProto, UnsetFieldsTakeTheApiDefaults) {
  auto s = to_engine_settings(base(), SettingsLimits{});
  ASSERT_TRUE(s) << s.status().message();
  const pipeline::BakeSettings d = pipeline::default_settings();
  EXPECT_EQ(s->atlas.resolution, 0);
  EXPECT_EQ(s->atlas.texel_density, 40);
  EXPECT_EQ(s->atlas.max_resolution, 1024);
  EXPECT_EQ(s->samples_per_texel, 16u);
  EXPECT_EQ(s->max_bounces, d.max_bounces);
  EXPECT_EQ(s->seed, 1u);
  EXPECT_EQ(s->dilation_texels, 2);
  EXPECT_EQ(s->progress_interval_s, 1.0);
  EXPECT_FALSE(s->lights.sun.enabled);
  EXPECT_EQ(s->job.snapshot_interval_s, 5.0);
  EXPECT_EQ(s->job.snapshot_max_side, 512);
  // 0 is a value for these: no sample rule, a hard sun.
  v1::BakeSettings p;
  p.set_time_budget_s(3);
  p.mutable_sun()->set_illuminance(2);
  s = to_engine_settings(p, SettingsLimits{});
  ASSERT_TRUE(s) << s.status().message();
  EXPECT_EQ(s->samples_per_texel, 0u);
  EXPECT_TRUE(s->lights.sun.enabled);
  EXPECT_EQ(s->lights.sun.angular_radius_degrees, 0.0f);
  EXPECT_EQ(s->lights.sun.direction.y, -1.0f);
  // The default size respects the daemon's limit; rate limits are raised.
  p = base();
  p.set_progress_interval_s(0.001);
  s = to_engine_settings(p, SettingsLimits{256});
  ASSERT_TRUE(s) << s.status().message();
  EXPECT_EQ(s->atlas.resolution, 0);
  EXPECT_EQ(s->atlas.max_resolution, 256);
  EXPECT_EQ(s->atlas.resolution_limit, 256);
  EXPECT_EQ(s->progress_interval_s, 0.05);
  // The CLI's default bake leaves max_resolution unset, so a daemon with a
  // lower limit takes it instead of refusing the default.
  auto sent = to_proto_settings(pipeline::default_settings());
  ASSERT_TRUE(sent) << sent.status().message();
  EXPECT_EQ(sent->max_resolution(), 0u);
  EXPECT_EQ(sent->texel_density(), 0.0f);
  auto taken = to_engine_settings(sent.value(), SettingsLimits{256});
  ASSERT_TRUE(taken) << taken.status().message();
  EXPECT_EQ(taken->atlas.max_resolution, 256);
  EXPECT_EQ(taken->atlas.texel_density, 40);
  // A page size given past the limit is refused, naming both.
  p.set_max_resolution(512);
  EXPECT_EQ(to_engine_settings(p, SettingsLimits{256}).status().message(),
            "settings.max_resolution: 512 exceeds the daemon's limit --max-resolution=256");
}

// Distributed bakes: shards sample uniformly. adaptive left unset is off
// for a shard; adaptive = true given is refused, naming the field; shards of
// one bake share the fingerprint, which leaves the shard fields out.
TEST(SettingsProto, ShardsAreUniformAndShareTheFingerprint) {
  v1::BakeSettings p = base();
  p.set_samples_per_texel(64);
  p.set_shard_count(4);
  p.set_shard_index(3);
  auto s = to_engine_settings(p, SettingsLimits{});
  ASSERT_TRUE(s) << s.status().message();
  EXPECT_EQ(s->shard_count, 4u);
  EXPECT_EQ(s->shard_index, 3u);
  EXPECT_FALSE(s->adaptive);
  EXPECT_EQ(s->shard_samples(), 16u);
  v1::BakeSettings other = p;
  other.set_shard_index(1);
  auto s1 = to_engine_settings(other, SettingsLimits{});
  ASSERT_TRUE(s1) << s1.status().message();
  EXPECT_EQ(pipeline::bake_fingerprint("scene", *s), pipeline::bake_fingerprint("scene", *s1));
  // The merged bake (shard_count 1, adaptive off) has the shards' fingerprint.
  pipeline::BakeSettings whole = *s;
  whole.shard_count = 1;
  whole.shard_index = 0;
  EXPECT_EQ(pipeline::bake_fingerprint("scene", whole), pipeline::bake_fingerprint("scene", *s));
  // What the API sends back for a shard round-trips.
  auto sent = to_proto_settings(*s);
  ASSERT_TRUE(sent) << sent.status().message();
  EXPECT_EQ(sent->shard_count(), 4u);
  EXPECT_EQ(sent->shard_index(), 3u);

  p.set_adaptive(true);
  auto refused = to_engine_settings(p, SettingsLimits{});
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(refused.status().message().find("settings.adaptive"), std::string::npos);
  p.set_adaptive(false);
  p.set_shard_index(4);
  refused = to_engine_settings(p, SettingsLimits{});
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.status().message().find("settings.shard_index"), std::string::npos);
  p.set_shard_index(0);
  p.set_shard_count(5000);
  refused = to_engine_settings(p, SettingsLimits{});
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.status().message().find("settings.shard_count"), std::string::npos);
  p.set_shard_count(2);
  p.add_encodings(v1::ENCODING_SG12);
  refused = to_engine_settings(p, SettingsLimits{});
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.status().message().find("settings.solver"), std::string::npos);
}

TEST(SettingsProto, RoundTripThroughTheApiKeepsTheBake) {
  pipeline::BakeSettings s = pipeline::default_settings();
  s.samples_per_texel = 64;
  s.max_bounces = 0;
  s.filter = pipeline::Filter::kGaussian;
  s.lights.sky.kind = pipeline::SkySettings::Kind::kConstant;
  s.lights.sky.color = {0.2f, 0.3f, 0.5f};
  s.lights.sun.enabled = true;
  s.lights.sun.direction = {1, -2, 0.5f};
  s.lights.sun.illuminance = 3;
  s.encodings.names = {"sh2", "ambient-dice9"};
  s.encodings.solver = pipeline::EncodingSolver::kProgressive;
  s.job.priority = -3;
  s.job.snapshot_format = pipeline::SnapshotFormat::kExr;
  auto p = to_proto_settings(s);
  ASSERT_TRUE(p) << p.status().message();
  EXPECT_EQ(p->encodings_size(), 2);
  EXPECT_EQ(p->solver(), v1::SOLVER_PROGRESSIVE);
  EXPECT_TRUE(p->has_max_bounces());
  auto back = to_engine_settings(p.value(), SettingsLimits{});
  ASSERT_TRUE(back) << back.status().message();
  EXPECT_EQ(back->describe(), s.describe());
  EXPECT_EQ(back->job.priority, -3);
  EXPECT_EQ(back->job.snapshot_format, pipeline::SnapshotFormat::kExr);
  // What the API cannot carry is refused, naming the field.
  s.dilation_texels = 0;
  EXPECT_EQ(to_proto_settings(s).status().message().rfind("settings.dilation_texels: 0 cannot", 0),
            0u);
}

// Per-node placements cross the API exactly (bits of the floats, the
// instance's presence) and are validated at submit, naming the entry.
TEST(SettingsProto, PlacementsRoundTripAndErrors) {
  pipeline::BakeSettings s = pipeline::default_settings();
  pipeline::NodePlacement a;
  a.node = 4;
  const float so[4] = {0.1f, 0.3f, 1.0f / 3.0f, 0.7f};
  for (int k = 0; k < 4; ++k) a.scale_offset[k] = so[k];
  pipeline::NodePlacement b = a;
  b.node = 5;
  b.element = 0;
  b.page = 2;
  s.node_placements = {a, b};
  auto p = to_proto_settings(s);
  ASSERT_TRUE(p) << p.status().message();
  ASSERT_EQ(p->placements_size(), 2);
  EXPECT_FALSE(p->placements(0).has_instance());
  EXPECT_TRUE(p->placements(1).has_instance());
  auto back = to_engine_settings(p.value(), SettingsLimits{});
  ASSERT_TRUE(back) << back.status().message();
  ASSERT_EQ(back->node_placements.size(), 2u);
  EXPECT_EQ(back->node_placements[0].element, -1);
  EXPECT_EQ(back->node_placements[1].element, 0);
  EXPECT_EQ(back->node_placements[1].page, 2);
  for (int k = 0; k < 4; ++k) EXPECT_EQ(back->node_placements[0].scale_offset[k], so[k]);
  // Placements shape the lightmap, so they are part of the settings the
  // checkpoint fingerprint covers.
  EXPECT_EQ(back->describe(), s.describe());
  EXPECT_NE(pipeline::bake_fingerprint("scene", s),
            pipeline::bake_fingerprint("scene", pipeline::default_settings()));

  v1::BakeSettings bad = base();
  auto* np = bad.add_placements();
  np->set_node(1);
  np->add_scale_offset(1);
  EXPECT_EQ(service_error(bad),
            "settings.placements[0].scale_offset: expected 4 values [sx, sy, ox, oy], got 1");
  for (int k = 0; k < 3; ++k) np->add_scale_offset(k == 0 ? 0.0f : 1.0f);
  EXPECT_NE(service_error(bad).find("settings.placements[0].scale_offset: must be 4 finite"),
            std::string::npos)
      << service_error(bad);
  np->set_scale_offset(1, 1);
  EXPECT_EQ(service_error(bad), "ok");
  np->set_page(5000);
  EXPECT_EQ(service_error(bad), "settings.placements[0].page: must be in [0, 1024)");
}

// Settings each in range whose product overflows a float are refused at
// submit, naming the field (they passed SubmitBake and failed the bake).
TEST(SettingsProto, ProductsThatOverflowAreRefusedAtSubmit) {
  v1::BakeSettings sky = base();
  sky.mutable_sky()->set_kind(v1::Sky::KIND_CONSTANT);
  for (float c : {3e38f, 1.0f, 1.0f}) sky.mutable_sky()->add_color(c);
  sky.mutable_sky()->set_intensity(10);
  EXPECT_EQ(
      service_error(sky).rfind("settings.sky.intensity: sky.color x sky.intensity overflows", 0),
      0u)
      << service_error(sky);
  sky.mutable_sky()->set_intensity(1);
  EXPECT_EQ(service_error(sky), "ok");
  v1::BakeSettings sun = base();
  sun.mutable_sun()->set_illuminance(1e30f);
  for (float c : {1e10f, 1.0f, 1.0f}) sun.mutable_sun()->add_color(c);
  EXPECT_EQ(service_error(sun).rfind("settings.sun.illuminance: sun.color x sun.illuminance", 0),
            0u)
      << service_error(sun);
}

}  // namespace
}  // namespace luxel::service
