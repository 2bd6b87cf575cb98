// libFuzzer target for the glTF importer: any byte string must give a Scene or
// an error Status, never a crash, a hang or unbounded memory.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "scene/gltf_import.h"
#include "scene/scene_stats.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  luxel::scene::ImportOptions options;
  // Lower limits than production so that libFuzzer's -rss_limit_mb catches
  // real leaks of memory, not a file that legitimately claims 1 GiB.
  options.max_accessor_elements = uint64_t{1} << 22;
  options.max_image_pixels = uint64_t{1} << 22;
  options.max_total_texture_pixels = uint64_t{1} << 23;
  options.require_lightmap_uvs = (size & 1) == 0;  // exercise both paths
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  auto scene = luxel::scene::import_gltf_memory(bytes, "", "fuzz", options);
  if (scene) {
    // The stats walk every index and UV: a scene that imports must be sound.
    (void)luxel::scene::compute_stats(*scene, 64);
  }
  return 0;
}
