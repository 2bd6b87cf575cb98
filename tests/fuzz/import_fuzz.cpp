// libFuzzer target for the glTF importer and lightmap UV generation: any byte
// string must give a Scene or an error Status, never a crash, a hang or
// unbounded memory; a scene that imports goes on through
// uv::generate_lightmap_uvs, which must give an error Status or a layout whose
// UVs are finite, inside the atlas and overlap-free at texel centres.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>
#include <vector>

#include "scene/gltf_import.h"
#include "scene/scene_stats.h"
#include "support/uv_layout_check.h"
#include "uv/generate.h"

namespace {

// Keeps one iteration to milliseconds: generation is about linear in
// triangles, and a 64^2 atlas bounds the packer and the overlap check.
constexpr size_t kMaxUvTriangles = 4096;
constexpr size_t kMaxUvInstances = 256;
void check_uv_generation(const luxel::scene::Scene& scene) {
  size_t triangles = 0;
  for (const luxel::scene::Instance& inst : scene.instances)
    if (inst.mesh >= 0 && static_cast<size_t>(inst.mesh) < scene.meshes.size())
      triangles += scene.meshes[static_cast<size_t>(inst.mesh)].triangle_count();
  if (triangles > kMaxUvTriangles || scene.instances.size() > kMaxUvInstances) return;
  luxel::uv::GenerateOptions options;
  options.atlas.resolution = 64;
  auto g = luxel::uv::generate_lightmap_uvs(scene, options);
  if (!g) return;  // an error Status is an answer
  const luxel::testing::LayoutCheck check = luxel::testing::check_layout(g->scene, g->atlas);
  // Every UV inside the atlas (zero-area triangles included: they collapse
  // onto a point of a chart), no texel centre in two triangles.
  if (g->atlas.width != 64 || g->atlas.height != 64 || check.outside_triangles != 0 ||
      check.overlapping_texels != 0 || check.outside_points != 0) {
    std::fprintf(stderr,
                 "uv generation: atlas %dx%d, %lld triangles and %lld points outside [0,1], %lld "
                 "overlapping texel centres\n",
                 g->atlas.width, g->atlas.height, check.outside_triangles, check.outside_points,
                 check.overlapping_texels);
    __builtin_trap();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  luxel::scene::ImportOptions options;
  // Lower limits than production so that libFuzzer's -rss_limit_mb catches
  // real leaks of memory, not a file that legitimately claims 1 GiB.
  options.max_accessor_elements = uint64_t{1} << 22;
  options.max_image_pixels = uint64_t{1} << 22;
  options.max_total_texture_pixels = uint64_t{1} << 23;
  options.max_import_bytes = uint64_t{256} << 20;  // the daemon default is GiBs
  options.require_lightmap_uvs = (size & 1) == 0;  // exercise both paths
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  auto scene = luxel::scene::import_gltf_memory(bytes, "", "fuzz", options);
  if (scene) {
    // The stats walk every index and UV: a scene that imports must be sound.
    (void)luxel::scene::compute_stats(*scene, 64);
    check_uv_generation(*scene);
  }
  return 0;
}
