#include "settings/settings_schema.h"

#include <cmath>
#include <nlohmann/json.hpp>
#include <set>
#include <type_traits>

#include "common/direction.h"
#include "settings/bake_settings.h"
#include "settings/schema_table.h"

namespace luxel::pipeline {
namespace {

using Type = SettingType;
using Scope = SettingScope;

std::vector<Setting> make_schema() {
  std::vector<Setting> t;
  schema::add_bake_settings(t);
  schema::add_scene_and_output_settings(t);
  return t;
}

std::string fmt_number(double x) {
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  if (std::isfinite(x) && x == std::floor(x) && std::fabs(x) < 1e15) return strprintf("%.0f", x);
  return strprintf("%g", x);
}

bool in_range(const Setting& st, double x) {
  if (st.zero_is_auto && x == 0) return true;
  if (st.min_open ? !(x > st.min) : !(x >= st.min)) return false;
  if (st.max_open ? !(x < st.max) : !(x <= st.max)) return false;
  return true;
}

// "in [0, 64]", ">= 0", "in [0, 90)", "> 0".
std::string range_phrase(const Setting& st) {
  const bool lo = std::isfinite(st.min), hi = std::isfinite(st.max);
  if (lo && hi)
    return strprintf("%sin %c%s, %s%c", st.zero_is_auto ? "0 (auto) or " : "",
                     st.min_open ? '(' : '[', fmt_number(st.min).c_str(),
                     fmt_number(st.max).c_str(), st.max_open ? ')' : ']');
  if (lo) return strprintf("%s %s", st.min_open ? ">" : ">=", fmt_number(st.min).c_str());
  if (hi) return strprintf("%s %s", st.max_open ? "<" : "<=", fmt_number(st.max).c_str());
  return "";
}

bool is_choice(const Setting& st, const std::string& name) {
  for (const char* c : st.choices)
    if (name == c) return true;
  return false;
}

std::string choice_list(const Setting& st) {
  std::string out;
  for (const char* c : st.choices) out += (out.empty() ? "" : ", ") + std::string(c);
  return out;
}

std::vector<std::string> split(const std::string& text, char sep) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (start <= text.size()) {
    size_t end = text.find(sep, start);
    if (end == std::string::npos) end = text.size();
    parts.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  return parts;
}

}  // namespace

const std::vector<Setting>& settings_schema() {
  static const std::vector<Setting> schema = make_schema();
  return schema;
}

const Setting* find_setting(const std::string& name) {
  for (const Setting& st : settings_schema())
    if (name == st.name) return &st;
  return nullptr;
}

BakeSettings default_settings() {
  BakeSettings s;
  for (const Setting& st : settings_schema()) st.set(s, st.default_value);
  return s;
}

Status check_setting(const Setting& st, const SettingValue& v) {
  auto bad = [&](const std::string& why) {
    return invalid_argument(strprintf("settings.%s: %s", st.name, why.c_str()));
  };
  switch (st.type) {
    case Type::kInt:
    case Type::kFloat: {
      const double x = v.number;
      if (!std::isfinite(x)) return bad("must be a finite number, got " + fmt_number(x));
      if (st.type == Type::kInt && x != std::floor(x))
        return bad("must be a whole number, got " + fmt_number(x));
      if (!in_range(st, x))
        return bad(
            strprintf("must be %s, got %s", range_phrase(st).c_str(), fmt_number(x).c_str()));
      return Status::ok();
    }
    case Type::kBool:
    case Type::kText:
      return Status::ok();
    case Type::kChoice:
      if (!is_choice(st, v.text))
        return bad(strprintf("'%s' is not one of %s", v.text.c_str(), choice_list(st).c_str()));
      return Status::ok();
    case Type::kChoiceList: {
      std::set<std::string> seen;
      for (const auto& n : v.list) {
        if (!is_choice(st, n))
          return bad(strprintf("'%s' is not one of %s", n.c_str(), choice_list(st).c_str()));
        if (!seen.insert(n).second) return bad(strprintf("'%s' is listed twice", n.c_str()));
      }
      if (double(v.list.size()) > st.max)
        return bad(
            strprintf("at most %s at once, got %zu", fmt_number(st.max).c_str(), v.list.size()));
      return Status::ok();
    }
    case Type::kVec3: {
      const Vec3 c = v.vec;
      const std::string got = strprintf("(%g, %g, %g)", c.x, c.y, c.z);
      if (!is_finite(c)) return bad("values must be finite, got " + got);
      for (int i = 0; i < 3; ++i)
        if (!in_range(st, c[i]))
          return bad(
              strprintf("each value must be %s, got %s", range_phrase(st).c_str(), got.c_str()));
      if (st.nonzero && c.x == 0 && c.y == 0 && c.z == 0) return bad("must not be zero");
      // The bake normalizes the vector and refuses one that does not survive
      // it (common/direction.h: a squared length past FLT_MAX or below the
      // smallest normal float), on whichever thread builds the light table.
      if (st.nonzero && !normalizable(c))
        return bad(
            "its squared length must be a normal single-precision float (about 1e-19 to 1e19 "
            "per component): it does not survive normalisation, got " +
            got);
      return Status::ok();
    }
  }
  return Status::ok();
}

Status apply_setting(BakeSettings& s, const Setting& st, SettingValue v) {
  LUXEL_RETURN_IF_ERROR(check_setting(st, v));
  if (st.raise_to > 0 && v.number > 0 && v.number < st.raise_to) v.number = st.raise_to;
  st.set(s, v);
  return Status::ok();
}

std::string format_setting_value(const Setting& st, const SettingValue& v) {
  switch (st.type) {
    case Type::kInt:
    case Type::kFloat:
      return fmt_number(v.number);
    case Type::kBool:
      return v.number != 0 ? "on" : "off";
    case Type::kChoice:
    case Type::kText:
      return v.text;
    case Type::kChoiceList: {
      std::string out;
      for (const auto& n : v.list) out += (out.empty() ? "" : ",") + n;
      return out;
    }
    case Type::kVec3:
      return strprintf("%g,%g,%g", v.vec.x, v.vec.y, v.vec.z);
  }
  return "";
}

Result<SettingValue> parse_setting_value(const Setting& st, const std::string& text) {
  auto number = [&](const std::string& t, double* out) {
    char* end = nullptr;
    *out = std::strtod(t.c_str(), &end);
    return !t.empty() && *end == '\0';
  };
  auto bad = [&](const char* expected) -> Status {
    return invalid_argument(
        strprintf("settings.%s: expected %s, got '%s'", st.name, expected, text.c_str()));
  };
  SettingValue v;
  switch (st.type) {
    case Type::kInt:
    case Type::kFloat:
      if (!number(text, &v.number)) return bad("a number");
      return v;
    case Type::kBool:
      if (text == "on" || text == "1" || text == "true") return SettingValue::of(1);
      if (text == "off" || text == "0" || text == "false") return SettingValue::of(0);
      return bad("on or off");
    case Type::kChoice:
    case Type::kText:
      return SettingValue::of_text(text);
    case Type::kChoiceList:
      for (auto& item : split(text, ','))
        if (!item.empty()) v.list.push_back(item);
      return v;
    case Type::kVec3: {
      auto parts = split(text, ',');
      double c[3];
      if (parts.size() != 3) return bad("three comma-separated numbers");
      for (int i = 0; i < 3; ++i)
        if (!number(parts[size_t(i)], &c[i])) return bad("three comma-separated numbers");
      return SettingValue::of_vec({float(c[0]), float(c[1]), float(c[2])});
    }
  }
  return bad("a value");
}

std::string describe_setting_value(const Setting& st, const SettingValue& v) {
  switch (st.type) {
    case Type::kInt:
      if (st.zero_is_auto && v.number == 0) return "auto";
      return strprintf("%lld", static_cast<long long>(v.number));
    case Type::kFloat:
      return strprintf("%g", v.number);
    case Type::kBool:
    case Type::kChoice:
    case Type::kText:
    case Type::kChoiceList:
    case Type::kVec3:
      break;
  }
  return format_setting_value(st, v);  // on/off, names, "a,b", "x,y,z" (%g)
}

bool same_setting_value(const Setting& st, const SettingValue& a, const SettingValue& b) {
  switch (st.type) {
    case Type::kInt:
    case Type::kFloat:
    case Type::kBool:
      return a.number == b.number;
    case Type::kChoice:
    case Type::kText:
      return a.text == b.text;
    case Type::kChoiceList:
      return a.list == b.list;
    case Type::kVec3:
      return a.vec.x == b.vec.x && a.vec.y == b.vec.y && a.vec.z == b.vec.z;
  }
  return false;
}

std::string describe_range(const Setting& st) {
  switch (st.type) {
    case Type::kChoice: {
      std::string out;
      for (const char* c : st.choices) out += (out.empty() ? "" : " | ") + std::string(c);
      return out;
    }
    case Type::kChoiceList:
      return strprintf("each of %s at most once, at most %s", choice_list(st).c_str(),
                       fmt_number(st.max).c_str());
    case Type::kVec3: {
      std::string r = range_phrase(st);
      std::string out = r.empty() ? "3 finite values" : "3 values, each " + r;
      return st.nonzero ? out + ", not all 0" : out;
    }
    case Type::kBool:
      return "on | off";
    case Type::kText:
      return "text";
    default: {
      std::string r = range_phrase(st);
      if (r.empty()) r = "finite";
      if (st.raise_to > 0)
        r += strprintf(", below %s raised to it", fmt_number(st.raise_to).c_str());
      return r;
    }
  }
}

std::string settings_schema_json() {
  using nlohmann::json;
  json all = json::array();
  for (const Setting& st : settings_schema()) {
    static const char* kTypes[] = {"int", "float", "bool", "choice", "choice_list", "vec3", "text"};
    static const char* kScopes[] = {"everywhere", "local_only", "api_only"};
    json e = {{"name", st.name},
              {"type", kTypes[int(st.type)]},
              {"units", st.units},
              {"help", st.help},
              {"flag", st.flag ? st.flag : ""},
              {"range", describe_range(st)},
              {"scope", kScopes[int(st.scope)]},
              {"api_zero", st.api_zero == ApiZero::kValue ? "value" : "default"},
              {"api_note", st.api_note ? st.api_note : ""}};
    const SettingValue& d = st.default_value;
    switch (st.type) {
      case Type::kInt:
        e["default"] = static_cast<long long>(d.number);
        break;
      case Type::kFloat:
        e["default"] = d.number;
        break;
      case Type::kBool:
        e["default"] = d.number != 0;
        break;
      case Type::kChoice:
      case Type::kText:
        e["default"] = d.text;
        break;
      case Type::kChoiceList:
        e["default"] = d.list;
        break;
      case Type::kVec3:
        e["default"] = {d.vec.x, d.vec.y, d.vec.z};
        break;
    }
    if (std::isfinite(st.min)) e["min"] = st.min;
    if (std::isfinite(st.max)) e["max"] = st.max;
    if (!st.choices.empty()) {
      std::vector<std::string> choices(st.choices.begin(), st.choices.end());
      e["choices"] = choices;
    }
    all.push_back(e);
  }
  return json({{"format", "luxel-settings-schema"}, {"version", 1}, {"settings", all}}).dump(1) +
         "\n";
}

}  // namespace luxel::pipeline
