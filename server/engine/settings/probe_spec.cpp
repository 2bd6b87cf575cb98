#include "settings/probe_spec.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace luxel::probes {

namespace {

Status bad_spec(const std::string& spec, const std::string& why) {
  return invalid_argument(
      "settings.probes: '" + spec + "': " + why +
      " (grid:S, grid:S:box=x0,y0,z0,x1,y1,z1, file:P.json, adaptive:S, nodes)");
}

Result<float> parse_float(const std::string& text) {
  try {
    size_t used = 0;
    const float v = std::stof(text, &used);
    if (used != text.size() || !std::isfinite(v)) return invalid_argument("not a number");
    return v;
  } catch (...) {
    return invalid_argument("not a number");
  }
}

}  // namespace

Result<PlacementSettings> parse_probe_spec(const std::string& spec) {
  PlacementSettings s;
  if (spec == choice_name(PlacementMode::kNodes)) {
    s.mode = PlacementMode::kNodes;
    return s;
  }
  const size_t colon = spec.find(':');
  if (colon == std::string::npos) return bad_spec(spec, "no mode");
  const std::string mode = spec.substr(0, colon), rest = spec.substr(colon + 1);
  const auto parsed = parse_choice<PlacementMode>(mode);
  // nodes takes no argument: "nodes:..." is not a spec.
  if (!parsed || *parsed == PlacementMode::kNodes)
    return bad_spec(spec, "unknown mode '" + mode + "'");
  s.mode = *parsed;
  if (s.mode == PlacementMode::kFile) {
    if (rest.empty()) return bad_spec(spec, "no file");
    s.file = rest;
    return s;
  }
  const size_t next = rest.find(':');
  auto spacing = parse_float(rest.substr(0, next));
  if (!spacing || !(spacing.value() > 0)) return bad_spec(spec, "spacing must be a number > 0");
  s.spacing = spacing.value();
  if (next == std::string::npos) return s;
  const std::string option = rest.substr(next + 1);
  if (option.rfind("box=", 0) != 0) return bad_spec(spec, "unknown option '" + option + "'");
  std::vector<float> v;
  size_t at = 4;
  while (at <= option.size()) {
    const size_t comma = std::min(option.find(',', at), option.size());
    auto x = parse_float(option.substr(at, comma - at));
    if (!x) return bad_spec(spec, "box takes six numbers");
    v.push_back(x.value());
    at = comma + 1;
  }
  if (v.size() != 6) return bad_spec(spec, "box takes six numbers");
  s.has_box = true;
  s.box.extend(Vec3{v[0], v[1], v[2]});
  s.box.extend(Vec3{v[3], v[4], v[5]});
  return s;
}

std::string describe_probe_spec(const PlacementSettings& s) {
  if (s.mode == PlacementMode::kFile) return "file:" + s.file;
  if (s.mode == PlacementMode::kNodes) return "nodes";
  std::string out = strprintf("%s:%g", choice_name(s.mode), double(s.spacing));
  if (s.has_box)
    out +=
        strprintf(":box=%g,%g,%g,%g,%g,%g", double(s.box.lo.x), double(s.box.lo.y),
                  double(s.box.lo.z), double(s.box.hi.x), double(s.box.hi.y), double(s.box.hi.z));
  return out;
}

}  // namespace luxel::probes
