// Scenes on disk, content-addressed by their scene id (scene_id_of below):
//
//   <data>/scenes/<id>/scene.gltf|scene.glb   the main file
//   <data>/scenes/<id>/<uri>                  external resources of a .gltf
//   <data>/scenes/<id>/info.json              SceneInfo (protobuf JSON)
//   <data>/staging/<random>/                      uploads in progress
//
// An upload is written into its own staging folder; only a verified and
// imported upload is renamed into scenes/ (one atomic rename of the whole
// folder, info.json written inside it first), so scenes/ never holds a
// partial scene. Staging folders left by a crash are removed by open().
#pragma once

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "common/status.h"
#include "luxel/v1/luxel.pb.h"
#include "scene/scene.h"
#include "service/scene_cache.h"

namespace luxel::service {

// The scene id of an upload (common/scene_id.h, the rule in luxel.proto's
// header comment; the CLI computes it with the same function). Covering the
// resources means a changed .bin is a new scene instead of an already_stored
// hit that keeps the old bytes. The header's hashes must already be verified
// against the bytes (SceneUpload does that).
std::string scene_id_of(const v1::SceneUploadHeader& header);

class SceneStore {
 public:
  // Creates the folders, removes stale staging folders, loads every scene's
  // info. `cache` bounds the imported scenes kept in memory (SceneCache);
  // `importer` replaces scene::import_gltf_file (tests); `import` are its
  // options otherwise (the daemon's import memory pool, which must outlive
  // the store, and timeout).
  static Result<std::unique_ptr<SceneStore>> open(const std::string& data_dir,
                                                  SceneCacheLimits cache = {},
                                                  SceneCache::Importer importer = {},
                                                  scene::ImportOptions import = {});

  // A new, empty staging folder for one upload.
  Result<std::string> new_staging_dir();

  // Name of the main file inside a scene folder for a format.
  static const char* main_file_name(v1::SceneFormat format);

  // Takes a staging folder whose files are verified (size and sha256): when
  // the scene is already stored, removes the folder and returns the stored
  // info with already_stored = true; otherwise imports and validates the main
  // file (INVALID_ARGUMENT naming what fails; RESOURCE_EXHAUSTED over the
  // import memory budget, DEADLINE_EXCEEDED past the import timeout), writes info.json and moves
  // the folder into place. The folder is gone afterwards in every case. The validated import is
  // kept in the scene cache for the first bake.
  Result<v1::SceneInfo> commit(const std::string& staging_dir, const v1::SceneUploadHeader& header,
                               uint64_t stored_bytes);

  Result<v1::SceneInfo> get(const std::string& scene_id) const;
  std::vector<v1::SceneInfo> list() const;
  bool contains(const std::string& scene_id) const;
  // NOT_FOUND for an unknown id. The caller checks that no bake uses it.
  Status remove(const std::string& scene_id);
  // Path of the main file of a stored scene.
  std::string main_file_path(const v1::SceneInfo& info) const;
  // The imported scene of a stored scene: from the cache, or imported from
  // its main file (and cached). Errors are the importer's.
  Result<std::shared_ptr<const scene::Scene>> load_scene(const v1::SceneInfo& info);
  // Importer runs (commit's validation and load_scene's misses), for tests.
  size_t scene_imports() const { return cache_.imports(); }
  size_t size() const;

 private:
  SceneStore(std::string data_dir, SceneCacheLimits cache, SceneCache::Importer importer,
             scene::ImportOptions import);
  std::string scene_dir(const std::string& scene_id) const;

  std::string scenes_dir_, staging_dir_;
  mutable std::mutex mu_;
  std::map<std::string, v1::SceneInfo> scenes_;
  SceneCache cache_;
};

}  // namespace luxel::service
