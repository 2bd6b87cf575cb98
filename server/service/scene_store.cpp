#include "service/scene_store.h"

#include <google/protobuf/util/json_util.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "common/scene_id.h"
#include "common/sha256.h"
#include "scene/scene_stats.h"
#include "service/files.h"
#include "service/log.h"

namespace luxel::service {

namespace fs = std::filesystem;
namespace pbu = google::protobuf::util;

namespace {

void fill_statistics(const scene::SceneStats& s, v1::SceneStatistics* out) {
  out->set_meshes(static_cast<uint32_t>(s.meshes));
  out->set_instances(static_cast<uint32_t>(s.instances));
  out->set_triangles(s.world_triangles);
  out->set_materials(static_cast<uint32_t>(s.materials));
  out->set_textures(static_cast<uint32_t>(s.textures));
  out->set_point_lights(static_cast<uint32_t>(s.point_lights));
  out->set_spot_lights(static_cast<uint32_t>(s.spot_lights));
  out->set_directional_lights(static_cast<uint32_t>(s.directional_lights));
  out->set_emissive_triangles(s.emissive_triangles);
  if (!s.world_bounds.empty()) {
    for (float v : {s.world_bounds.lo.x, s.world_bounds.lo.y, s.world_bounds.lo.z})
      out->add_bounds_min(v);
    for (float v : {s.world_bounds.hi.x, s.world_bounds.hi.y, s.world_bounds.hi.z})
      out->add_bounds_max(v);
  }
  out->set_lightmap_uv_coverage(s.lightmap_coverage);
}

Result<v1::SceneInfo> load_info(const std::string& path) {
  auto text = read_whole_file(path);
  if (!text) return text.status();
  v1::SceneInfo info;
  auto st = pbu::JsonStringToMessage(text.value(), &info);
  if (!st.ok()) return data_loss(strprintf("%s: %s", path.c_str(), st.ToString().c_str()));
  return info;
}

}  // namespace

std::string scene_id_of(const v1::SceneUploadHeader& header) {
  std::vector<SceneIdResource> resources;
  for (const auto& r : header.resources()) resources.push_back({r.uri(), r.size(), r.sha256()});
  return scene_id(header.sha256(), std::move(resources));
}

SceneStore::SceneStore(std::string data_dir, SceneCacheLimits cache, SceneCache::Importer importer,
                       scene::ImportOptions import)
    : scenes_dir_(data_dir + "/scenes"),
      staging_dir_(data_dir + "/staging"),
      cache_(cache, std::move(importer), std::move(import)) {}

Result<std::unique_ptr<SceneStore>> SceneStore::open(const std::string& data_dir,
                                                     SceneCacheLimits cache,
                                                     SceneCache::Importer importer,
                                                     scene::ImportOptions import) {
  std::unique_ptr<SceneStore> store(
      new SceneStore(data_dir, cache, std::move(importer), std::move(import)));
  LUXEL_RETURN_IF_ERROR(make_directories(store->scenes_dir_));
  LUXEL_RETURN_IF_ERROR(make_directories(store->staging_dir_));
  std::error_code ec;
  // Uploads that were in flight when the daemon stopped: never committed.
  for (const auto& entry : fs::directory_iterator(store->staging_dir_, ec)) {
    log_event("staging_removed", {{"path", entry.path().string()}});
    remove_tree(entry.path().string());
  }
  for (const auto& entry : fs::directory_iterator(store->scenes_dir_, ec)) {
    const std::string id = entry.path().filename().string();
    auto info = load_info(entry.path().string() + "/info.json");
    if (!is_sha256_hex(id) || !info) {
      // Cannot come from commit() (info.json is written before the rename);
      // left alone for an operator rather than deleted.
      log_event("scene_unreadable",
                {{"path", entry.path().string()},
                 {"error", info ? "not a scene id" : info.status().to_string()}});
      continue;
    }
    info->set_already_stored(false);
    store->scenes_[id] = info.value();
  }
  log_event("scene_store_opened", {{"scenes", std::to_string(store->scenes_.size())}});
  return store;
}

Result<std::string> SceneStore::new_staging_dir() {
  const std::string dir = staging_dir_ + "/" + random_hex_id();
  LUXEL_RETURN_IF_ERROR(make_directories(dir));
  return dir;
}

const char* SceneStore::main_file_name(v1::SceneFormat format) {
  return format == v1::SCENE_FORMAT_GLB ? "scene.glb" : "scene.gltf";
}

std::string SceneStore::scene_dir(const std::string& scene_id) const {
  return scenes_dir_ + "/" + scene_id;
}

std::string SceneStore::main_file_path(const v1::SceneInfo& info) const {
  return scene_dir(info.scene_id()) + "/" + main_file_name(info.format());
}

namespace {

// `text` with `dir`'s path taken out: the importer names files by their
// path on this machine, the client knows them by the upload's own names
// (the main file by the upload's name, `main_name`).
std::string without_dir(std::string text, const std::string& dir, const std::string& main_path,
                        const std::string& main_name) {
  for (size_t at = text.find(main_path); at != std::string::npos;
       at = text.find(main_path, at + main_name.size()))
    text.replace(at, main_path.size(), main_name);
  for (const std::string& prefix : {dir + "/", dir}) {
    for (size_t at = text.find(prefix); at != std::string::npos; at = text.find(prefix, at))
      text.replace(at, prefix.size(), prefix == dir ? "." : "");
  }
  return text;
}

// Coordinates past this magnitude leave a float no room for the offsets a
// ray needs off a surface (an ulp at 1e16 is about 1e9 units), and past
// FLT_MAX they are infinite: every bake of such a scene fails.
constexpr float kMaxCoordinate = 1e16f;

// A scene no bake can use is refused at upload, naming the upload's file:
// no triangle to bake or to put probes around, or world coordinates past
// kMaxCoordinate.
Status check_bakeable(const scene::SceneStats& stats, const std::string& name) {
  if (stats.world_triangles == 0)
    return invalid_argument(
        strprintf("scene '%s' failed validation: it has no triangles (every bake needs geometry)",
                  name.c_str()));
  const Bounds3& b = stats.world_bounds;
  for (int a = 0; a < 3; ++a)
    if (!(std::fabs(b.lo[a]) <= kMaxCoordinate && std::fabs(b.hi[a]) <= kMaxCoordinate))
      return invalid_argument(strprintf(
          "scene '%s' failed validation: world coordinates reach %g (axis %c), past +-%g; scale "
          "the scene down",
          name.c_str(), double(std::max(std::fabs(b.lo[a]), std::fabs(b.hi[a]))), "xyz"[a],
          double(kMaxCoordinate)));
  return Status::ok();
}

}  // namespace

Result<v1::SceneInfo> SceneStore::commit(const std::string& staging_dir,
                                         const v1::SceneUploadHeader& header,
                                         uint64_t stored_bytes) {
  struct Cleanup {
    std::string dir;
    ~Cleanup() {
      if (!dir.empty()) remove_tree(dir);
    }
  } cleanup{staging_dir};

  const std::string id = scene_id_of(header);
  if (auto existing = get(id)) {
    existing->set_already_stored(true);
    return existing;
  }
  const std::string main_path = staging_dir + "/" + main_file_name(header.format());
  auto imported = cache_.import(main_path);
  if (!imported) {
    const Status& st = imported.status();
    // Whatever the importer says, the upload is what is wrong, unless it ran
    // into a limit (the import memory budget, the import timeout).
    const StatusCode code =
        st.code() == StatusCode::kResourceExhausted || st.code() == StatusCode::kDeadlineExceeded
            ? st.code()
            : StatusCode::kInvalidArgument;
    return Status(
        code, strprintf(code == StatusCode::kInvalidArgument ? "scene '%s' failed validation: %s"
                                                             : "scene '%s' was not imported: %s",
                        header.name().c_str(),
                        without_dir(st.message(), staging_dir, main_path, header.name()).c_str()));
  }
  const scene::SceneStats stats = scene::compute_stats(imported.value());
  if (Status st = check_bakeable(stats, header.name()); !st.is_ok()) return st;

  v1::SceneInfo info;
  info.set_scene_id(id);
  info.set_name(header.name());
  info.set_format(header.format());
  info.set_size(stored_bytes);
  info.set_uploaded_at(unix_now());
  fill_statistics(stats, info.mutable_statistics());
  for (const auto& w : imported->import_stats.warnings)
    info.add_warnings(without_dir(w, staging_dir, main_path, header.name()));

  std::string json;
  pbu::JsonPrintOptions options;
  options.add_whitespace = true;
  if (auto st = pbu::MessageToJsonString(info, &json, options); !st.ok())
    return internal_error("scene info to JSON: " + st.ToString());
  LUXEL_RETURN_IF_ERROR(write_file_atomic(staging_dir + "/info.json", json));
  LUXEL_RETURN_IF_ERROR(fsync_directory(staging_dir));

  std::lock_guard<std::mutex> lock(mu_);
  if (auto it = scenes_.find(id); it != scenes_.end()) {  // a concurrent upload won
    v1::SceneInfo existing = it->second;
    existing.set_already_stored(true);
    return existing;
  }
  LUXEL_RETURN_IF_ERROR(rename_durable(staging_dir, scene_dir(id)));
  cleanup.dir.clear();
  scenes_[id] = info;
  // What load_scene would import from the stored file: the importer names the
  // scene after the path it was given (manifests carry it).
  imported->source_name = main_file_path(info);
  cache_.put(id, std::make_shared<const scene::Scene>(std::move(imported.value())));
  return info;
}

Result<std::shared_ptr<const scene::Scene>> SceneStore::load_scene(const v1::SceneInfo& info) {
  return cache_.get_or_import(info.scene_id(), main_file_path(info));
}

Result<v1::SceneInfo> SceneStore::get(const std::string& scene_id) const {
  std::lock_guard<std::mutex> lock(mu_);
  auto it = scenes_.find(scene_id);
  if (it == scenes_.end()) return not_found(strprintf("scene_id: no scene '%s'", scene_id.c_str()));
  return it->second;
}

std::vector<v1::SceneInfo> SceneStore::list() const {
  std::lock_guard<std::mutex> lock(mu_);
  std::vector<v1::SceneInfo> out;
  for (const auto& [id, info] : scenes_) out.push_back(info);
  return out;
}

bool SceneStore::contains(const std::string& scene_id) const {
  std::lock_guard<std::mutex> lock(mu_);
  return scenes_.count(scene_id) > 0;
}

Status SceneStore::remove(const std::string& scene_id) {
  std::lock_guard<std::mutex> lock(mu_);
  if (!scenes_.count(scene_id))
    return not_found(strprintf("scene_id: no scene '%s'", scene_id.c_str()));
  // Rename out of scenes/ first (atomic), then delete at leisure: a crash in
  // between leaves a staging folder, which the next start removes.
  const std::string doomed = staging_dir_ + "/deleted-" + random_hex_id();
  LUXEL_RETURN_IF_ERROR(rename_durable(scene_dir(scene_id), doomed));
  scenes_.erase(scene_id);
  cache_.erase(scene_id);
  remove_tree(doomed);
  return Status::ok();
}

size_t SceneStore::size() const {
  std::lock_guard<std::mutex> lock(mu_);
  return scenes_.size();
}

}  // namespace luxel::service
