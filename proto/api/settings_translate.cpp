#include "api/settings_translate.h"

#include <algorithm>
#include <cctype>
#include <map>

#include "common/hash.h"

namespace luxel::service {
namespace {

namespace pb = google::protobuf;
using pipeline::Setting;
using pipeline::SettingType;
using pipeline::SettingValue;

Status bad(const Setting& st, const std::string& why) {
  return invalid_argument(strprintf("settings.%s: %s", st.name, why.c_str()));
}

std::vector<std::string> split_path(const std::string& path) {
  std::vector<std::string> parts;
  size_t start = 0;
  for (size_t dot; (dot = path.find('.', start)) != std::string::npos; start = dot + 1)
    parts.push_back(path.substr(start, dot - start));
  parts.push_back(path.substr(start));
  return parts;
}

// "KIND_" for Sky.Kind (zero value KIND_NONE), "SOLVER_" for Solver.
std::string enum_prefix(const pb::EnumDescriptor* e) {
  const std::string& zero = e->FindValueByNumber(0)->name();
  return zero.substr(0, zero.rfind('_') + 1);
}

// KIND_CONSTANT -> "constant", SOLVER_PROGRESSIVE_NN -> "progressive-nn".
std::string choice_of(const pb::EnumValueDescriptor* v) {
  std::string name = v->name().substr(enum_prefix(v->type()).size());
  for (char& c : name)
    c = c == '_' ? '-' : static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return name;
}

// The message holding the setting's field, or nullptr when a parent message
// is absent (every field below it is then unset).
const pb::Message* holder(const pb::Message& root, const std::string& path) {
  const pb::Message* m = &root;
  const auto parts = split_path(path);
  for (size_t i = 0; i + 1 < parts.size(); ++i) {
    const pb::FieldDescriptor* f = m->GetDescriptor()->FindFieldByName(parts[i]);
    if (!m->GetReflection()->HasField(*m, f)) return nullptr;
    m = &m->GetReflection()->GetMessage(*m, f);
  }
  return m;
}

pb::Message* mutable_holder(pb::Message& root, const std::string& path) {
  pb::Message* m = &root;
  const auto parts = split_path(path);
  for (size_t i = 0; i + 1 < parts.size(); ++i)
    m = m->GetReflection()->MutableMessage(m, m->GetDescriptor()->FindFieldByName(parts[i]));
  return m;
}

double get_number(const pb::Message& m, const pb::FieldDescriptor* f) {
  const pb::Reflection* r = m.GetReflection();
  switch (f->cpp_type()) {
    case pb::FieldDescriptor::CPPTYPE_INT32:
      return r->GetInt32(m, f);
    case pb::FieldDescriptor::CPPTYPE_UINT32:
      return r->GetUInt32(m, f);
    case pb::FieldDescriptor::CPPTYPE_INT64:
      return double(r->GetInt64(m, f));
    case pb::FieldDescriptor::CPPTYPE_UINT64:
      return double(r->GetUInt64(m, f));
    case pb::FieldDescriptor::CPPTYPE_FLOAT:
      return r->GetFloat(m, f);
    case pb::FieldDescriptor::CPPTYPE_DOUBLE:
      return r->GetDouble(m, f);
    case pb::FieldDescriptor::CPPTYPE_BOOL:
      return r->GetBool(m, f) ? 1 : 0;
    default:
      return 0;
  }
}

void set_number(pb::Message& m, const pb::FieldDescriptor* f, double x) {
  const pb::Reflection* r = m.GetReflection();
  switch (f->cpp_type()) {
    case pb::FieldDescriptor::CPPTYPE_INT32:
      r->SetInt32(&m, f, static_cast<int32_t>(x));
      break;
    case pb::FieldDescriptor::CPPTYPE_UINT32:
      r->SetUInt32(&m, f, static_cast<uint32_t>(x));
      break;
    case pb::FieldDescriptor::CPPTYPE_INT64:
      r->SetInt64(&m, f, static_cast<int64_t>(x));
      break;
    case pb::FieldDescriptor::CPPTYPE_UINT64:
      r->SetUInt64(&m, f, static_cast<uint64_t>(x));
      break;
    case pb::FieldDescriptor::CPPTYPE_FLOAT:
      r->SetFloat(&m, f, static_cast<float>(x));
      break;
    case pb::FieldDescriptor::CPPTYPE_DOUBLE:
      r->SetDouble(&m, f, x);
      break;
    case pb::FieldDescriptor::CPPTYPE_BOOL:
      r->SetBool(&m, f, x != 0);
      break;
    default:
      break;
  }
}

// The value of a present field, in the schema's terms.
Result<SettingValue> read_value(const Setting& st, const pb::Message& m,
                                const pb::FieldDescriptor* f) {
  const pb::Reflection* r = m.GetReflection();
  SettingValue v;
  switch (st.type) {
    case SettingType::kInt:
    case SettingType::kFloat:
    case SettingType::kBool:
      v.number = get_number(m, f);
      break;
    case SettingType::kText:
      v.text = r->GetString(m, f);
      break;
    case SettingType::kChoice: {
      const int n = r->GetEnumValue(m, f);
      const auto* e = f->enum_type()->FindValueByNumber(n);
      if (!e)
        return bad(st, strprintf("unknown value %d of %s", n, f->enum_type()->name().c_str()));
      v.text = choice_of(e);
      break;
    }
    case SettingType::kChoiceList:
      for (int i = 0; i < r->FieldSize(m, f); ++i) {
        const int n = r->GetRepeatedEnumValue(m, f, i);
        const auto* e = f->enum_type()->FindValueByNumber(n);
        if (!e || n == 0)
          return bad(st, strprintf("unknown value %d of %s", n, f->enum_type()->name().c_str()));
        v.list.push_back(choice_of(e));
      }
      break;
    case SettingType::kVec3: {
      const int n = r->FieldSize(m, f);
      if (n != 3) return bad(st, strprintf("expected 3 values, got %d", n));
      v.vec = Vec3{r->GetRepeatedFloat(m, f, 0), r->GetRepeatedFloat(m, f, 1),
                   r->GetRepeatedFloat(m, f, 2)};
      break;
    }
  }
  return v;
}

bool is_zero(const Setting& st, const SettingValue& v) {
  switch (st.type) {
    case SettingType::kChoiceList:
      return v.list.empty();
    case SettingType::kText:
      return v.text.empty();
    case SettingType::kChoice:
      return false;  // enums are written by name
    case SettingType::kVec3:
      return false;
    default:
      return v.number == 0;
  }
}

// Reads every API setting into `s`. A value that breaks its setting's rule is
// not stored; its error is kept in `errors` (reported only if the setting is
// active, e.g. sun.* only with a sun).
void read_settings(const v1::BakeSettings& in, const SettingsLimits& limits,
                   pipeline::BakeSettings& s, std::map<std::string, Status>* errors) {
  s = pipeline::default_settings();
  s.atlas.resolution_limit = limits.max_resolution;
  bool max_resolution_given = false;
  for (const Setting& st : pipeline::settings_schema()) {
    if (!st.in_api()) continue;
    const pb::FieldDescriptor* f = proto_field(st.name);
    const pb::Message* m = holder(in, st.name);
    const bool present = m && (f->is_repeated() ? m->GetReflection()->FieldSize(*m, f) > 0
                                                : m->GetReflection()->HasField(*m, f));
    SettingValue v;  // the zero value
    if (present) {
      auto read = read_value(st, *m, f);
      if (!read) {
        if (errors) errors->emplace(st.name, read.status());
        continue;
      }
      v = std::move(read.value());
    } else if (st.api_zero == pipeline::ApiZero::kDefault) {
      continue;  // keeps the schema's default
    }
    if (present && st.name == std::string("max_resolution")) max_resolution_given = true;
    if (errors) {
      if (Status c = pipeline::check_setting(st, v); !c.is_ok()) {
        errors->emplace(st.name, c);
        continue;
      }
    }
    (void)pipeline::apply_setting(s, st, std::move(v));
  }
  // Rules of the API form (documented in luxel.proto): the sun is on when it
  // has an illuminance; the default page size respects the daemon's limit.
  s.lights.sun.enabled = s.lights.sun.illuminance > 0;
  // Shards sample uniformly (their accumulators must merge exactly): adaptive
  // sampling left unset is off for them; adaptive=true given is refused by
  // validate_settings.
  if (s.sharded() && !in.has_adaptive()) s.adaptive = false;
  if (!max_resolution_given)
    s.atlas.max_resolution = std::min(s.atlas.max_resolution, limits.max_resolution);
  if (!s.job.reference_bake_id.empty()) s.reference_name = "bake " + s.job.reference_bake_id;
  // Placements: a list of structures, outside the schema's scalar settings
  // (validate_settings checks them and names placements[i]).
  for (int i = 0; i < in.placements_size(); ++i) {
    const v1::NodePlacement& in_p = in.placements(i);
    pipeline::NodePlacement p;
    p.node = in_p.node() > 0x7fffffffu ? 0x7fffffff : static_cast<int>(in_p.node());
    p.element = in_p.has_instance() ? static_cast<int>(std::min(in_p.instance(), 0x7fffffffu)) : -1;
    p.page = static_cast<int>(std::min(in_p.page(), 0x7fffffffu));
    if (in_p.scale_offset_size() != 4) {
      if (errors)
        errors->emplace("placements", invalid_argument(strprintf(
                                          "settings.placements[%d].scale_offset: expected 4 "
                                          "values [sx, sy, ox, oy], got %d",
                                          i, in_p.scale_offset_size())));
      continue;
    }
    for (int k = 0; k < 4; ++k) p.scale_offset[k] = in_p.scale_offset(k);
    s.node_placements.push_back(p);
  }
}

}  // namespace

const pb::FieldDescriptor* proto_field(const std::string& path) {
  const pb::Descriptor* d = v1::BakeSettings::descriptor();
  const pb::FieldDescriptor* f = nullptr;
  for (const auto& part : split_path(path)) {
    if (!d) return nullptr;
    f = d->FindFieldByName(part);
    if (!f) return nullptr;
    d = f->message_type();
  }
  return f;
}

std::string proto_enum_name(const pb::EnumDescriptor* e, const std::string& choice) {
  std::string name = enum_prefix(e) + choice;
  for (char& c : name)
    c = c == '-' ? '_' : static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return name;
}

Result<pipeline::BakeSettings> to_engine_settings(const v1::BakeSettings& in,
                                                  const SettingsLimits& limits) {
  pipeline::BakeSettings s;
  std::map<std::string, Status> errors;
  read_settings(in, limits, s, &errors);
  for (const Setting& st : pipeline::settings_schema()) {
    auto e = errors.find(st.name);
    if (e != errors.end() && st.is_active(s)) return e->second;
  }
  if (auto e = errors.find("placements"); e != errors.end()) return e->second;
  LUXEL_RETURN_IF_ERROR(pipeline::validate_settings(s, "the daemon's limit --max-resolution"));
  return s;
}

pipeline::BakeSettings stored_engine_settings(const v1::BakeSettings& in,
                                              const SettingsLimits& limits) {
  pipeline::BakeSettings s;
  read_settings(in, limits, s, nullptr);
  return s;
}

Result<v1::BakeSettings> to_proto_settings(const pipeline::BakeSettings& s) {
  v1::BakeSettings out;
  for (const Setting& st : pipeline::settings_schema()) {
    if (!st.in_api() || !st.is_active(s)) continue;
    const pb::FieldDescriptor* f = proto_field(st.name);
    const SettingValue v = st.get(s);
    // A default the API reads from 0 is left unset, so that the daemon
    // resolves it under its own limits (max_resolution: 1024, or a lower
    // --max-resolution) as it does for any client.
    if (st.api_zero == pipeline::ApiZero::kDefault && !f->has_presence() && !f->is_repeated() &&
        st.type != SettingType::kChoice && !is_zero(st, v) &&
        pipeline::same_setting_value(st, v, st.default_value))
      continue;
    if (is_zero(st, v)) {
      if (st.api_zero == pipeline::ApiZero::kDefault && !f->has_presence() &&
          !is_zero(st, st.default_value))
        return bad(st, strprintf("0 cannot be sent to luxeld: the API reads 0 as the default %s "
                                 "(bake with --local)",
                                 pipeline::format_setting_value(st, st.default_value).c_str()));
      if (!f->has_presence() || f->is_repeated()) continue;
    }
    pb::Message& m = *mutable_holder(out, st.name);
    const pb::Reflection* r = m.GetReflection();
    switch (st.type) {
      case SettingType::kInt:
      case SettingType::kFloat:
      case SettingType::kBool:
        set_number(m, f, v.number);
        break;
      case SettingType::kText:
        r->SetString(&m, f, v.text);
        break;
      case SettingType::kChoice: {
        const auto* e = f->enum_type()->FindValueByName(proto_enum_name(f->enum_type(), v.text));
        if (!e) return bad(st, strprintf("'%s' is not available through the API", v.text.c_str()));
        r->SetEnumValue(&m, f, e->number());
        break;
      }
      case SettingType::kChoiceList:
        for (const auto& name : v.list)
          r->AddEnumValue(
              &m, f,
              f->enum_type()->FindValueByName(proto_enum_name(f->enum_type(), name))->number());
        break;
      case SettingType::kVec3:
        for (int i = 0; i < 3; ++i) r->AddFloat(&m, f, v.vec[i]);
        break;
    }
  }
  for (const pipeline::NodePlacement& p : s.node_placements) {
    v1::NodePlacement* out_p = out.add_placements();
    out_p->set_node(static_cast<uint32_t>(std::max(p.node, 0)));
    if (p.element >= 0) out_p->set_instance(static_cast<uint32_t>(p.element));
    for (float v : p.scale_offset) out_p->add_scale_offset(v);
    out_p->set_page(static_cast<uint32_t>(std::max(p.page, 0)));
  }
  return out;
}

v1::SnapshotFormat to_proto(pipeline::SnapshotFormat f) {
  switch (f) {
    case pipeline::SnapshotFormat::kPng:
      return v1::SNAPSHOT_FORMAT_PNG;
    case pipeline::SnapshotFormat::kExr:
      return v1::SNAPSHOT_FORMAT_EXR;
    case pipeline::SnapshotFormat::kNone:
      return v1::SNAPSHOT_FORMAT_NONE;
  }
  return v1::SNAPSHOT_FORMAT_PNG;
}

v1::BakeProgress to_proto(const pipeline::BakeProgress& p) {
  v1::BakeProgress out;
  out.set_elapsed_s(p.elapsed_s);
  out.set_paths(p.paths);
  out.set_mean_spp(p.mean_spp);
  out.set_min_spp(p.min_spp);
  out.set_error(p.error);
  out.set_eta_s(p.eta_s);
  out.set_fraction(p.fraction);
  out.set_rmse(p.rmse);
  out.set_rel_mse(p.rel_mse);
  return out;
}

}  // namespace luxel::service
