// Device-memory tiling of a bake (the way Unity's progressive lightmapper
// bounds GPU memory): the covered texels are cut into tiles of consecutive
// covered slots, each small enough that
//   fixed bytes + tile slots * per-slot bytes + the tile's sample-info words
// stays within the device-memory budget, and no per-slot buffer of a tile
// exceeds the device's largest allocation (CL_DEVICE_MAX_MEM_ALLOC_SIZE).
// Fixed bytes are everything not sized by the covered texels: the scene,
// BVH, lights, textures, path state (the batch), sort and compaction
// scratch, a reference image.
//
// Turn policy (docs/architecture.md "Device memory and tiles"): the tiles
// take turns on the device one after another, each baked to the stopping
// rules on its own texels, and its state is read back into the result
// before the next tile's buffers are cleared:
//   samples   every tile to samples_per_texel (exact, as untiled);
//   time      tile i stops at time_budget_s * (covered slots up to and
//             including tile i) / covered texels of elapsed tracing time, so
//             time left over by a fast tile passes on to the next;
//   error     every tile to target_error on its own texels; the bake's mean
//             (or RMS) over all texels is then within target_error too.
// Per-texel sample sequences depend only on (texel, sample index, seed), so
// under the samples rule a tiled bake gives the bits of the untiled one.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "atlas/sample_info.h"
#include "common/status.h"

namespace luxel::pipeline {

struct Tile {
  size_t begin = 0, end = 0;  // covered slots [begin, end)
  size_t words = 0;           // sample-info words of its texels
};

struct MemoryModel {
  size_t budget = 0;            // device-memory budget, bytes
  size_t max_alloc = 0;         // the device's largest allocation, bytes
  size_t fixed = 0;             // bytes not sized by the covered texels
  size_t per_slot = 0;          // bytes per covered slot, all buffers together
  size_t largest_per_slot = 0;  // bytes per slot of the largest per-slot buffer
  bool tileable = true;         // false: the bake must fit in one tile
  const char* why_not = "";     // the reason when not tileable (names the setting)
};

struct TilePlan {
  std::vector<Tile> tiles;
  size_t max_slots = 0, max_words = 0;  // what the tile buffers must hold
  size_t device_bytes = 0;              // fixed + tile buffers: the planned peak
};

// The tiles of info.covered_texels under the model. One tile when
// everything fits. RESOURCE_EXHAUSTED naming the budget (and the setting)
// when the fixed bytes alone exceed it, when one texel does not fit, or
// when more than one tile is needed and the bake is not tileable.
Result<TilePlan> plan_tiles(const atlas::SampleInfo& info, const MemoryModel& model);

// The default budget: min(80 % of the device's global memory, 4 GiB).
size_t default_memory_budget(uint64_t global_mem_bytes);

}  // namespace luxel::pipeline
