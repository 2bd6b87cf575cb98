#include "output/manifest.h"

#include <charconv>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <system_error>

#include "common/atomic_file.h"

namespace luxel::output {
namespace {

using Json = nlohmann::ordered_json;

// A float as the double with the shortest decimal form that reads back as the
// same float, so 0.3f is written "0.3" rather than "0.30000001192092896".
double json_float(float f) {
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, f);
  if (ec != std::errc()) return f;
  const double shortest = std::strtod(std::string(buf, end).c_str(), nullptr);
  return static_cast<float>(shortest) == f ? shortest : static_cast<double>(f);
}

Json instance_to_json(const Manifest::Instance& in, int pages) {
  Json j{{"name", in.name},
         {"node", in.node},
         {"mesh", in.mesh},
         {"scale", {json_float(in.scale[0]), json_float(in.scale[1])}},
         {"offset", {json_float(in.offset[0]), json_float(in.offset[1])}},
         {"rect", {in.rect[0], in.rect[1], in.rect[2], in.rect[3]}}};
  if (pages > 1) j["page"] = in.page;
  return j;
}

Json stats_to_json(const Manifest::Stats& s) {
  // nlohmann writes non-finite doubles as null.
  Json j{{"seconds", s.seconds},
         {"paths", s.paths},
         {"mean_spp", s.mean_spp},
         {"min_spp", s.min_spp},
         {"error_estimate", s.error_estimate},
         {"nonfinite_dropped", s.nonfinite_dropped},
         {"termination", s.termination},
         {"covered_texels", static_cast<uint64_t>(s.covered_texels)}};
  if (s.rmse >= 0) {
    j["rmse"] = s.rmse;
    j["rel_mse"] = s.rel_mse;
  }
  if (s.peak_device_bytes > 0) {
    j["peak_device_bytes"] = s.peak_device_bytes;
    j["device_memory_budget"] = s.device_memory_budget;
    j["tiles"] = s.tiles;
  }
  if (s.batch_paths > 0) j["batch_paths"] = s.batch_paths;
  return j;
}

Json to_json(const Manifest& m) {
  Json j;
  j["format"] = kManifestFormat;
  j["version"] = kManifestVersion;
  j["luxel_version"] = m.luxel_version;
  j["git_revision"] = m.git_revision;
  j["scene_name"] = m.scene_name;
  j["scene_sha256"] = m.scene_sha256;
  j["width"] = m.width;
  j["height"] = m.height;
  j["encoding"] = m.encoding;
  j["units"] = m.units;
  j["uv_set"] = m.uv_set;
  if (!m.uv_sets.empty()) j["uv_sets"] = m.uv_sets;
  j["atlas_mode"] = m.atlas_mode;
  j["dilation_texels"] = m.dilation_texels;
  j["instances"] = Json::array();
  if (m.pages > 1) j["pages"] = m.pages;
  if (m.texels_per_unit > 0) j["texels_per_unit"] = m.texels_per_unit;
  for (const auto& in : m.instances) j["instances"].push_back(instance_to_json(in, m.pages));
  j["files"] = Json::array();
  for (const auto& f : m.files) {
    Json file{
        {"role", f.role}, {"path", f.path}, {"format", f.format}, {"description", f.description}};
    if (f.page >= 0) file["page"] = f.page;
    j["files"].push_back(file);
  }
  j["settings"] = Json::object();
  for (const auto& [key, value] : m.settings) j["settings"][key] = value;
  j["features"] = m.features;
  j["device"] = m.device;
  if (!m.intersector.empty()) j["intersector"] = m.intersector;
  if (!m.import_warnings.empty()) j["import_warnings"] = m.import_warnings;
  j["stats"] = stats_to_json(m.stats);
  if (!m.uv_layout_json.empty()) j["uv_layout"] = Json::parse(m.uv_layout_json);
  if (!m.denoise_json.empty()) j["denoise"] = Json::parse(m.denoise_json);
  if (!m.seam_stitch_json.empty()) j["seam_stitch"] = Json::parse(m.seam_stitch_json);
  if (!m.encodings_json.empty()) {
    j["encodings"] = Json::array();
    for (const auto& e : m.encodings_json) j["encodings"].push_back(Json::parse(e));
  }
  return j;
}

// Typed, validated access to the members of one JSON object. Errors name the
// source (`what`) and the full field path, e.g. "instances[2].rect".
class Fields {
 public:
  Fields(const Json& object, std::string where, const std::string& what)
      : obj_(object), where_(std::move(where)), what_(what) {}

  std::string path(const std::string& key) const {
    return where_.empty() ? key : where_ + "." + key;
  }

  Status error(const std::string& key, const std::string& problem) const {
    return invalid_argument(
        strprintf("%s: field '%s' %s", what_.c_str(), path(key).c_str(), problem.c_str()));
  }

  Status member(const std::string& key, const Json*& out) const {
    auto it = obj_.find(key);
    if (it == obj_.end()) return error(key, "is missing");
    out = &*it;
    return Status::ok();
  }

  Status string(const std::string& key, std::string& out, bool non_empty = false) const {
    const Json* v = nullptr;
    LUXEL_RETURN_IF_ERROR(member(key, v));
    if (!v->is_string()) return error(key, "must be a string");
    out = v->get<std::string>();
    if (non_empty && out.empty()) return error(key, "must not be empty");
    return Status::ok();
  }

  Status integer(const std::string& key, int& out, int min = INT_MIN, int max = INT_MAX) const {
    const Json* v = nullptr;
    LUXEL_RETURN_IF_ERROR(member(key, v));
    return as_int(*v, key, out, min, max);
  }

  Status unsigned64(const std::string& key, uint64_t& out) const {
    const Json* v = nullptr;
    LUXEL_RETURN_IF_ERROR(member(key, v));
    if (v->is_number_unsigned()) {
      out = v->get<uint64_t>();
      return Status::ok();
    }
    return error(key, "must be a non-negative integer");
  }

  // A number, or null for a non-finite value (read as NaN).
  Status real(const std::string& key, double& out) const {
    const Json* v = nullptr;
    LUXEL_RETURN_IF_ERROR(member(key, v));
    if (v->is_null()) {
      out = std::numeric_limits<double>::quiet_NaN();
      return Status::ok();
    }
    if (!v->is_number()) return error(key, "must be a number or null");
    out = v->get<double>();
    return Status::ok();
  }

  Status finite_floats(const std::string& key, float* out, size_t n) const {
    const Json* v = nullptr;
    LUXEL_RETURN_IF_ERROR(member(key, v));
    const std::string problem = strprintf("must be an array of %zu finite numbers", n);
    if (!v->is_array() || v->size() != n) return error(key, problem);
    for (size_t i = 0; i < n; ++i) {
      const Json& e = (*v)[i];
      if (!e.is_number() || !std::isfinite(e.get<double>())) return error(key, problem);
      out[i] = e.get<float>();
    }
    return Status::ok();
  }

  Status ints(const std::string& key, int* out, size_t n, int min) const {
    const Json* v = nullptr;
    LUXEL_RETURN_IF_ERROR(member(key, v));
    if (!v->is_array() || v->size() != n)
      return error(key, strprintf("must be an array of %zu integers", n));
    for (size_t i = 0; i < n; ++i)
      LUXEL_RETURN_IF_ERROR(as_int((*v)[i], key, out[i], min, INT_MAX));
    return Status::ok();
  }

  Status array(const std::string& key, const Json*& out) const {
    LUXEL_RETURN_IF_ERROR(member(key, out));
    return out->is_array() ? Status::ok() : error(key, "must be an array");
  }

  Status object(const std::string& key, const Json*& out) const {
    LUXEL_RETURN_IF_ERROR(member(key, out));
    return out->is_object() ? Status::ok() : error(key, "must be an object");
  }

 private:
  Status as_int(const Json& v, const std::string& key, int& out, int min, int max) const {
    const std::string problem = strprintf("must be an integer in [%d, %d]", min, max);
    if (!v.is_number_integer()) return error(key, problem);
    // nlohmann stores non-negative integers as unsigned: compare in 64 bits.
    if (v.is_number_unsigned() && v.get<uint64_t>() > static_cast<uint64_t>(max))
      return error(key, problem);
    const int64_t value = v.get<int64_t>();
    if (value < min || value > max) return error(key, problem);
    out = static_cast<int>(value);
    return Status::ok();
  }

  const Json& obj_;
  std::string where_;
  const std::string& what_;
};

Status read_instance(const Json& j, const std::string& where, const std::string& what,
                     const Manifest& m, Manifest::Instance& in) {
  if (!j.is_object())
    return invalid_argument(
        strprintf("%s: field '%s' must be an object", what.c_str(), where.c_str()));
  Fields f(j, where, what);
  LUXEL_RETURN_IF_ERROR(f.string("name", in.name));
  LUXEL_RETURN_IF_ERROR(f.integer("node", in.node, -1));
  LUXEL_RETURN_IF_ERROR(f.integer("mesh", in.mesh, -1));
  LUXEL_RETURN_IF_ERROR(f.finite_floats("scale", in.scale, 2));
  LUXEL_RETURN_IF_ERROR(f.finite_floats("offset", in.offset, 2));
  LUXEL_RETURN_IF_ERROR(f.ints("rect", in.rect, 4, 0));
  if (j.contains("page")) LUXEL_RETURN_IF_ERROR(f.integer("page", in.page, 0, m.pages - 1));
  if (int64_t{in.rect[0]} + in.rect[2] > m.width || int64_t{in.rect[1]} + in.rect[3] > m.height)
    return f.error("rect", strprintf("[%d, %d, %d, %d] leaves the %d x %d lightmap", in.rect[0],
                                     in.rect[1], in.rect[2], in.rect[3], m.width, m.height));
  return Status::ok();
}

Status read_file_entry(const Json& j, const std::string& where, const std::string& what,
                       Manifest::File& file) {
  if (!j.is_object())
    return invalid_argument(
        strprintf("%s: field '%s' must be an object", what.c_str(), where.c_str()));
  Fields f(j, where, what);
  LUXEL_RETURN_IF_ERROR(f.string("role", file.role, true));
  LUXEL_RETURN_IF_ERROR(f.string("path", file.path, true));
  LUXEL_RETURN_IF_ERROR(f.string("format", file.format));
  if (j.contains("page")) LUXEL_RETURN_IF_ERROR(f.integer("page", file.page, 0));
  return f.string("description", file.description);
}

Status read_stats(const Json& j, const std::string& what, Manifest::Stats& s) {
  Fields f(j, "stats", what);
  uint64_t covered = 0;
  LUXEL_RETURN_IF_ERROR(f.real("seconds", s.seconds));
  LUXEL_RETURN_IF_ERROR(f.unsigned64("paths", s.paths));
  LUXEL_RETURN_IF_ERROR(f.real("mean_spp", s.mean_spp));
  LUXEL_RETURN_IF_ERROR(f.real("min_spp", s.min_spp));
  LUXEL_RETURN_IF_ERROR(f.real("error_estimate", s.error_estimate));
  LUXEL_RETURN_IF_ERROR(f.unsigned64("nonfinite_dropped", s.nonfinite_dropped));
  LUXEL_RETURN_IF_ERROR(f.string("termination", s.termination));
  LUXEL_RETURN_IF_ERROR(f.unsigned64("covered_texels", covered));
  s.covered_texels = static_cast<size_t>(covered);
  if (j.contains("rmse")) {
    LUXEL_RETURN_IF_ERROR(f.real("rmse", s.rmse));
    LUXEL_RETURN_IF_ERROR(f.real("rel_mse", s.rel_mse));
  }
  if (j.contains("peak_device_bytes")) {
    LUXEL_RETURN_IF_ERROR(f.unsigned64("peak_device_bytes", s.peak_device_bytes));
    LUXEL_RETURN_IF_ERROR(f.unsigned64("device_memory_budget", s.device_memory_budget));
    LUXEL_RETURN_IF_ERROR(f.unsigned64("tiles", s.tiles));
  }
  if (j.contains("batch_paths")) LUXEL_RETURN_IF_ERROR(f.unsigned64("batch_paths", s.batch_paths));
  return Status::ok();
}

Status read_manifest_json(const Json& j, const std::string& what, Manifest& m) {
  if (!j.is_object())
    return invalid_argument(strprintf("%s: the manifest must be a JSON object", what.c_str()));
  Fields f(j, "", what);
  std::string format;
  LUXEL_RETURN_IF_ERROR(f.string("format", format));
  if (format != kManifestFormat)
    return f.error("format", strprintf("is '%s', expected '%s'", format.c_str(), kManifestFormat));
  int version = 0;
  LUXEL_RETURN_IF_ERROR(f.integer("version", version, 1));
  if (version != kManifestVersion)
    return f.error("version",
                   strprintf("is %d; this build reads version %d", version, kManifestVersion));
  LUXEL_RETURN_IF_ERROR(f.string("luxel_version", m.luxel_version, true));
  LUXEL_RETURN_IF_ERROR(f.string("git_revision", m.git_revision));
  LUXEL_RETURN_IF_ERROR(f.string("scene_name", m.scene_name));
  LUXEL_RETURN_IF_ERROR(f.string("scene_sha256", m.scene_sha256));
  LUXEL_RETURN_IF_ERROR(f.integer("width", m.width, 1));
  LUXEL_RETURN_IF_ERROR(f.integer("height", m.height, 1));
  m.pages = 1;
  if (j.contains("pages")) LUXEL_RETURN_IF_ERROR(f.integer("pages", m.pages, 1));
  m.texels_per_unit = 0;
  if (j.contains("texels_per_unit"))
    LUXEL_RETURN_IF_ERROR(f.real("texels_per_unit", m.texels_per_unit));
  LUXEL_RETURN_IF_ERROR(f.string("encoding", m.encoding, true));
  LUXEL_RETURN_IF_ERROR(f.string("units", m.units, true));
  LUXEL_RETURN_IF_ERROR(f.string("uv_set", m.uv_set, true));
  if (j.contains("uv_sets")) {
    const Json* sets = nullptr;
    LUXEL_RETURN_IF_ERROR(f.object("uv_sets", sets));
    for (const auto& [name, count] : sets->items()) {
      if (!count.is_number_unsigned())
        return f.error("uv_sets." + name, "is not a primitive count");
      m.uv_sets[name] = count.get<uint64_t>();
    }
  }
  LUXEL_RETURN_IF_ERROR(f.string("atlas_mode", m.atlas_mode));
  if (m.atlas_mode != "shared" && m.atlas_mode != "packed" && m.atlas_mode != "generated" &&
      m.atlas_mode != "placed")
    return f.error("atlas_mode",
                   strprintf("is '%s', expected 'shared', 'packed', 'generated' or 'placed'",
                             m.atlas_mode.c_str()));
  LUXEL_RETURN_IF_ERROR(f.integer("dilation_texels", m.dilation_texels, 0));

  const Json* list = nullptr;
  LUXEL_RETURN_IF_ERROR(f.array("instances", list));
  m.instances.resize(list->size());
  for (size_t i = 0; i < list->size(); ++i)
    LUXEL_RETURN_IF_ERROR(
        read_instance((*list)[i], strprintf("instances[%zu]", i), what, m, m.instances[i]));
  LUXEL_RETURN_IF_ERROR(f.array("files", list));
  m.files.resize(list->size());
  for (size_t i = 0; i < list->size(); ++i)
    LUXEL_RETURN_IF_ERROR(
        read_file_entry((*list)[i], strprintf("files[%zu]", i), what, m.files[i]));

  const Json* settings = nullptr;
  LUXEL_RETURN_IF_ERROR(f.object("settings", settings));
  m.settings.clear();
  Fields setting_fields(*settings, "settings", what);
  for (const auto& item : settings->items())
    LUXEL_RETURN_IF_ERROR(setting_fields.string(item.key(), m.settings[item.key()]));
  LUXEL_RETURN_IF_ERROR(f.string("features", m.features));
  LUXEL_RETURN_IF_ERROR(f.string("device", m.device));
  if (j.contains("intersector")) LUXEL_RETURN_IF_ERROR(f.string("intersector", m.intersector));
  if (j.contains("import_warnings")) {
    const Json* warnings = nullptr;
    LUXEL_RETURN_IF_ERROR(f.array("import_warnings", warnings));
    m.import_warnings.clear();
    for (size_t i = 0; i < warnings->size(); ++i) {
      if (!(*warnings)[i].is_string())
        return invalid_argument(
            strprintf("%s: field 'import_warnings[%zu]' must be a string", what.c_str(), i));
      m.import_warnings.push_back((*warnings)[i].get<std::string>());
    }
  }
  if (j.contains("uv_layout")) {
    const Json* uv = nullptr;
    LUXEL_RETURN_IF_ERROR(f.object("uv_layout", uv));
    m.uv_layout_json = uv->dump();
  }
  if (j.contains("denoise")) {
    const Json* dn = nullptr;
    LUXEL_RETURN_IF_ERROR(f.object("denoise", dn));
    m.denoise_json = dn->dump();
  }
  if (j.contains("seam_stitch")) {
    const Json* seams = nullptr;
    LUXEL_RETURN_IF_ERROR(f.object("seam_stitch", seams));
    m.seam_stitch_json = seams->dump();
  }
  if (j.contains("encodings")) {
    const Json& enc = j["encodings"];
    if (!enc.is_array())
      return invalid_argument(strprintf("%s: encodings: expected an array", what.c_str()));
    for (size_t i = 0; i < enc.size(); ++i) {
      if (!enc[i].is_object() || !enc[i].contains("name") || !enc[i]["name"].is_string())
        return invalid_argument(
            strprintf("%s: encodings[%zu]: expected an object with a name", what.c_str(), i));
      m.encodings_json.push_back(enc[i].dump());
    }
  }
  const Json* stats = nullptr;
  LUXEL_RETURN_IF_ERROR(f.object("stats", stats));
  return read_stats(*stats, what, m.stats);
}

}  // namespace

Result<Manifest> manifest_from_json(const std::string& text, const std::string& what) {
  Json doc;
  try {
    doc = Json::parse(text);
  } catch (const Json::parse_error& e) {
    return data_loss(strprintf("%s: not valid JSON: %s", what.c_str(), e.what()));
  }
  Manifest m;
  LUXEL_RETURN_IF_ERROR(read_manifest_json(doc, what, m));
  return m;
}

namespace {

// Parses what was written with the reader's rules: a manifest that could not
// be read back is never written, and the error names the field.
Result<std::string> serialize(const Manifest& manifest, const std::string& what) {
  std::string text = to_json(manifest).dump(2) + "\n";
  auto check = manifest_from_json(text, what);
  if (!check) return check.status();
  return text;
}

}  // namespace

Result<std::string> manifest_to_json(const Manifest& manifest) {
  return serialize(manifest, "manifest");
}

Status write_manifest(const std::string& path, const Manifest& manifest) {
  if (path.empty()) return invalid_argument("write_manifest: empty output path");
  auto text = serialize(manifest, path);
  if (!text) return text.status();
  return write_file_atomic(path, text->data(), text->size());
}

Result<Manifest> read_manifest(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    return not_found(strprintf("%s: no such manifest file", path.c_str()));
  // A manifest is a few kilobytes; refuse anything absurd before reading it.
  constexpr uintmax_t kMaxBytes = 64u << 20;
  const uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec || size > kMaxBytes)
    return invalid_argument(strprintf("%s: manifest is larger than 64 MiB", path.c_str()));
  std::ifstream in(path, std::ios::binary);
  if (!in) return invalid_argument(strprintf("%s: cannot open the manifest", path.c_str()));
  std::ostringstream text;
  text << in.rdbuf();
  return manifest_from_json(text.str(), path);
}

}  // namespace luxel::output
