#include "service/scene_cache.h"

#include <utility>

#include "scene/gltf_import.h"

namespace luxel::service {
namespace {

template <typename T>
uint64_t vector_bytes(const std::vector<T>& v) {
  return uint64_t{v.capacity()} * sizeof(T);
}

}  // namespace

uint64_t scene_bytes(const scene::Scene& scene) {
  uint64_t n = sizeof(scene::Scene);
  for (const auto& m : scene.meshes)
    n += sizeof m + vector_bytes(m.positions) + vector_bytes(m.normals) + vector_bytes(m.tangents) +
         vector_bytes(m.uv0) + vector_bytes(m.uv1) + vector_bytes(m.indices) +
         vector_bytes(m.triangle_material);
  for (const auto& t : scene.textures)
    n += sizeof t + vector_bytes(t.rgba8) + vector_bytes(t.rgba16f);
  n += vector_bytes(scene.instances) + vector_bytes(scene.materials) + vector_bytes(scene.lights);
  return n;
}

SceneCache::SceneCache(SceneCacheLimits limits, Importer importer, scene::ImportOptions import)
    : limits_(limits),
      importer_(importer ? std::move(importer) : Importer([import](const std::string& path) {
        return scene::import_gltf_file(path, import);
      })) {}

Result<scene::Scene> SceneCache::import(const std::string& path) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    ++imports_;
  }
  return importer_(path);
}

void SceneCache::put(const std::string& scene_id, std::shared_ptr<const scene::Scene> scene) {
  std::lock_guard<std::mutex> lock(mu_);
  put_locked(scene_id, std::move(scene));
}

void SceneCache::put_locked(const std::string& scene_id,
                            std::shared_ptr<const scene::Scene> scene) {
  if (auto it = index_.find(scene_id); it != index_.end()) {
    bytes_ -= it->second->bytes;
    lru_.erase(it->second);
    index_.erase(it);
  }
  const uint64_t bytes = scene_bytes(*scene);
  if (limits_.max_scenes == 0 || bytes > limits_.max_bytes) return;
  lru_.push_front({scene_id, std::move(scene), bytes});
  index_[scene_id] = lru_.begin();
  bytes_ += bytes;
  while (lru_.size() > limits_.max_scenes || bytes_ > limits_.max_bytes) {
    bytes_ -= lru_.back().bytes;
    index_.erase(lru_.back().id);
    lru_.pop_back();
  }
}

Result<std::shared_ptr<const scene::Scene>> SceneCache::get_or_import(const std::string& scene_id,
                                                                      const std::string& path) {
  std::unique_lock<std::mutex> lock(mu_);
  // Another thread importing the same id: its result serves this call too.
  loaded_.wait(lock, [&] { return loading_.count(scene_id) == 0; });
  if (auto it = index_.find(scene_id); it != index_.end()) {
    lru_.splice(lru_.begin(), lru_, it->second);
    return it->second->scene;
  }
  loading_.insert(scene_id);
  ++imports_;
  // Clears the loading mark however the import ends (an error, bad_alloc).
  struct Loading {
    SceneCache& cache;
    const std::string& id;
    std::unique_lock<std::mutex>& lock;
    ~Loading() {
      if (!lock.owns_lock()) lock.lock();
      cache.loading_.erase(id);
      cache.loaded_.notify_all();
    }
  } loading{*this, scene_id, lock};
  lock.unlock();
  auto imported = importer_(path);
  lock.lock();
  if (!imported) return imported.status();
  auto scene = std::make_shared<const scene::Scene>(std::move(imported.value()));
  put_locked(scene_id, scene);
  return scene;
}

void SceneCache::erase(const std::string& scene_id) {
  std::lock_guard<std::mutex> lock(mu_);
  auto it = index_.find(scene_id);
  if (it == index_.end()) return;
  bytes_ -= it->second->bytes;
  lru_.erase(it->second);
  index_.erase(it);
}

size_t SceneCache::imports() const {
  std::lock_guard<std::mutex> lock(mu_);
  return imports_;
}

size_t SceneCache::size() const {
  std::lock_guard<std::mutex> lock(mu_);
  return lru_.size();
}

uint64_t SceneCache::bytes() const {
  std::lock_guard<std::mutex> lock(mu_);
  return bytes_;
}

}  // namespace luxel::service
