// What a bake will need, known before anything is laid out or allocated:
// the lightmap's size from texel_density x the scene's surface, and the
// device memory of the batch (paths_per_iteration) against the device's
// largest allocation and the memory budget. Run at submit (the service's
// SubmitBake, the CLI before `bake --local`) so an impossible bake is
// refused with RESOURCE_EXHAUSTED naming the setting and the bytes instead
// of FAILING once queued; the bake's own memory plan (bake.cpp,
// plan_memory) runs the same path-state check with the same per-path
// bytes, so the two never disagree.
//
// The estimate refuses only what cannot fit: figures that depend on the
// layout (covered texels, packing) are lower bounds here, and the memory
// plan at bake time remains the exact check (tiles, per-texel state).
#pragma once

#include <cstddef>
#include <cstdint>

#include "common/status.h"
#include "device/context.h"
#include "scene/scene.h"
#include "settings/bake_settings.h"

namespace luxel::pipeline {

// 0: unknown (no device), that limit is not checked.
struct DeviceLimits {
  uint64_t global_mem_bytes = 0;
  uint64_t max_alloc_bytes = 0;
  unsigned compute_units = 0;  // sets the iteration cap (iteration_stops.h)
  bool is_gpu = false;         // sets the automatic batch (batch_paths_request)
  static DeviceLimits of(const device::DeviceInfo& info) {
    return {info.global_mem_bytes, info.max_alloc_bytes, info.compute_units, info.is_gpu};
  }
};

// Device bytes per path slot of the batch: every buffer BakeBuffers, the
// radix sort and stream compaction size by the batch, and the largest of
// them alone (one allocation). The per-path buffers cannot be tiled.
struct PathStateBytes {
  size_t per_path = 0;
  size_t largest = 0;
};
PathStateBytes path_state_bytes(bool basis_samples);

// Device bytes per covered texel of a tile (BakeBuffers::per_slot_bytes):
// covered texel, sample-info offset, offset buffer, mean, M2, weight,
// samples, a stats partial's share, the encodings' basis state, and with
// adaptive sampling its weight and a block sum's share, with the radiance
// cache its mean, and with guiding its histogram.
inline size_t texel_state_bytes(size_t basis_bytes_per_texel, bool adaptive,
                                bool radiance_cache = false, bool guiding = false) {
  return 4 + 4 + 4 + 16 + 16 + 8 + 4 + 1 + basis_bytes_per_texel + (adaptive ? 4 + 1 : 0) +
         (radiance_cache ? 16 : 0) + (guiding ? 128 : 0);
}

// The bake's memory budget: settings.device_memory_budget_mib, or the
// default of tile_plan.h for the device.
size_t memory_budget(const BakeSettings& settings, uint64_t global_mem_bytes);

// RESOURCE_EXHAUSTED naming paths_per_iteration and the bytes when `paths`
// path slots do not fit: the largest per-path buffer past the device's
// largest allocation, or the path state (plus `other_fixed` bytes known to
// be needed beside it) past the budget. A limit of 0 (device unknown) is
// not checked.
Status check_path_state(uint64_t paths, const PathStateBytes& bytes, size_t other_fixed,
                        size_t budget, uint64_t max_alloc);

// The batch a bake asks for: settings.paths_per_iteration, or for 0 (auto)
// the device's. CPUs: 2^18 paths, the fixed default of earlier releases (a
// PoCL iteration of it takes about 0.4 s on 2 cores; more only delays
// progress and stop requests). GPUs: 2^22 paths, halved while the path
// state would take more than half the budget or one buffer would pass the
// largest allocation, never below 2^18. On an H200, 2^18-path iterations
// leave the GPU idle between launches of tens of microseconds: 2^22 traced
// 2.5-2.6x more paths per second (docs/performance.md, "On a GPU"). The
// result depends only on the device and the settings, never on timing, so
// the bits stay those of the device. The iteration cap then trims it
// (iteration_path_cap).
uint64_t batch_paths_request(const BakeSettings& settings, const DeviceLimits& device,
                             const PathStateBytes& bytes, size_t budget);

struct ResourceEstimate {
  double surface_area = 0;     // world units^2 of the baked instances
  uint64_t min_texels = 0;     // the lightmap has at least these texels
  uint64_t min_covered = 0;    // and at least these covered ones (0: not known before layout)
  uint64_t max_texels = 0;     // the most --max-resolution (and pages) allow
  uint64_t batch_paths = 0;    // path slots of the batch buffers (at most)
  PathStateBytes per_path;     // bytes per path slot
  size_t path_bytes = 0;       // batch_paths x per_path.per_path
  size_t scene_bytes = 0;      // triangles, BVH, materials, textures (an estimate)
  size_t per_texel_bytes = 0;  // accumulation state per covered texel
  size_t budget = 0;           // device-memory budget of the bake
  // Device bytes with `covered` covered texels in one tile.
  size_t device_bytes(uint64_t covered) const {
    return scene_bytes + path_bytes + static_cast<size_t>(covered) * per_texel_bytes;
  }
};

// The estimate; RESOURCE_EXHAUSTED (naming the setting and the figure) when
// the batch does not fit the device; INVALID_ARGUMENT for settings that are
// invalid. A texel_density past what --max-resolution allows is no error:
// the layout lowers it (atlas.h), so the estimate counts at most max_texels.
Result<ResourceEstimate> estimate_bake_resources(const scene::Scene& scene,
                                                 const BakeSettings& settings,
                                                 const DeviceLimits& device);

}  // namespace luxel::pipeline
