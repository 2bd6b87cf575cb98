// Imported scenes kept in memory between the upload that validates a scene
// and the bakes that use it, so a bake of a just-uploaded scene does not
// import the glTF a second time.
//
// Keyed by scene id (content-addressed, so an id always names the same
// bytes and an entry never goes stale). Bounded by a count and by an estimate
// of the bytes the scenes hold; the least recently used entry goes first. A
// miss imports on demand (after a daemon restart the cache is empty). Entries
// are shared_ptr<const Scene>: a bake keeps its scene alive after eviction.
// Thread-safe; concurrent misses for one id wait for a single import.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>

#include "common/status.h"
#include "scene/gltf_import.h"
#include "scene/scene.h"

namespace luxel::service {

struct SceneCacheLimits {
  size_t max_scenes = 4;
  uint64_t max_bytes = uint64_t{1} << 30;  // scene_bytes() of all entries
};

// Host memory an imported scene holds (geometry, textures), an estimate for
// the cache bound.
uint64_t scene_bytes(const scene::Scene& scene);

class SceneCache {
 public:
  // Imports the main file at `path` (scene::import_gltf_file by default).
  using Importer = std::function<Result<scene::Scene>(const std::string& path)>;

  // `import`: the default importer's options (the daemon's shared import
  // memory pool and timeout, scene/import_budget.h).
  explicit SceneCache(SceneCacheLimits limits = {}, Importer importer = {},
                      scene::ImportOptions import = {});

  // Runs the importer (counted in imports()) without caching the result.
  Result<scene::Scene> import(const std::string& path);
  // Caches `scene` under `scene_id` unless it alone exceeds max_bytes;
  // evicts least recently used entries to stay within the limits.
  void put(const std::string& scene_id, std::shared_ptr<const scene::Scene> scene);
  // The cached scene, or an import of `path` (cached) on a miss.
  Result<std::shared_ptr<const scene::Scene>> get_or_import(const std::string& scene_id,
                                                            const std::string& path);
  void erase(const std::string& scene_id);

  size_t imports() const;  // importer runs so far
  size_t size() const;
  uint64_t bytes() const;

 private:
  struct Entry {
    std::string id;
    std::shared_ptr<const scene::Scene> scene;
    uint64_t bytes = 0;
  };
  void put_locked(const std::string& scene_id, std::shared_ptr<const scene::Scene> scene);

  const SceneCacheLimits limits_;
  const Importer importer_;
  mutable std::mutex mu_;
  std::condition_variable loaded_;
  std::list<Entry> lru_;  // most recently used first
  std::map<std::string, std::list<Entry>::iterator> index_;
  std::set<std::string> loading_;  // ids being imported by get_or_import
  uint64_t bytes_ = 0;
  size_t imports_ = 0;
};

}  // namespace luxel::service
