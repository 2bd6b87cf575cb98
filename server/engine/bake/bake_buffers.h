// The device memory of one bake: every buffer of the argument groups of
// kernels/shared/bake_args.h (scene, lights, textures, path state,
// accumulation, encodings) plus the ping-pong active lists and counts of
// the bounce loop. Scene buffers are uploaded once, path state is sized by
// the batch and accumulation by the lightmap, never by the sample count.
// Buffers of features the bake does not compile in are 16-byte
// placeholders (lights, sky, textures, encodings, reference).
#pragma once

#include "bake/bake_kernels.h"
#include "bake/bake_setup.h"
#include "device/context.h"
#include "scene/scene.h"
#include "settings/bake_settings.h"
#include "shards/checkpoint.h"

namespace luxel::pipeline {

// What the per-slot buffers hold: the covered texels of the largest tile
// and their sample-info words (bake/tile_plan.h).
struct TileCapacity {
  size_t slots = 0, words = 0;
};

class BakeBuffers {
 public:
  // Uploads the scene groups and allocates the rest, the per-slot buffers
  // for `cap`; load_tile then fills them. INVALID_ARGUMENT for a reference
  // of the wrong size.
  static Result<BakeBuffers> create(device::Context& ctx, const scene::Scene& scene,
                                    const BakeSetup& setup, const BakeSettings& settings,
                                    const TileCapacity& cap);
  // Bytes create() allocates beside the per-slot buffers (a dry run, no
  // device memory), and bytes per covered slot: all per-slot buffers, and
  // the largest one alone (the tile plan's memory model).
  static Result<size_t> fixed_bytes(device::Context& ctx, const scene::Scene& scene,
                                    const BakeSetup& setup, const BakeSettings& settings);
  static size_t per_slot_bytes(const BakeSetup& setup);
  static size_t largest_per_slot_bytes(const BakeSetup& setup);

  // Makes covered slots [begin, end) of the setup the current tile: uploads
  // their texels and sample-info records, sets args().params.covered_count
  // and clears the accumulation (state of slot k of the tile = covered slot
  // begin + k).
  // cancel: polled between the buffers' clears (a 2048^2 basis state is
  // hundreds of MB); a request ends it with cancelled_error.
  Status load_tile(device::Context& ctx, const BakeSetup& setup, size_t begin, size_t end,
                   CancelToken cancel = {});

  // The kernels' arguments (args().params is the bake's LuxBakeParams).
  BakeKernelArgs& args() { return args_; }
  const BakeKernelArgs& args() const { return args_; }

  // Bounce-loop bookkeeping (not kernel groups of their own): the batch's
  // path count for the sort, the count of paths with a texel, and the two
  // active lists with their live counts, swapped by compaction (§5.1).
  device::Buffer batch_count, path_count;
  device::Buffer active_a, active_b, count_a, count_b;

  size_t device_bytes() const { return device_bytes_; }

  // The accumulation state (mean, M2, weights, samples, encodings, dropped
  // count) to and from a checkpoint, per covered slot; width/height and the
  // covered count are checked on restore. covered: the setup's covered
  // texels, to compact a whole-image (version 1-2) checkpoint.
  // Slots [first, first + n) of the tile alone (the dropped count is the
  // tile's); the whole tile without them. cancel: polled between 64 MiB
  // pieces of the basis state (1 GB at 2048^2 with sh2 and sg12); a request
  // ends it with cancelled_error.
  Status read_state(device::Context& ctx, BakeCheckpoint& c, CancelToken cancel = {}) const;
  Status read_state(device::Context& ctx, BakeCheckpoint& c, size_t first, size_t n,
                    CancelToken cancel = {}) const;
  Status restore_state(device::Context& ctx, const BakeCheckpoint& c,
                       const std::vector<uint32_t>& covered);

 private:
  Status allocate(device::Context& ctx, const scene::Scene& scene, const BakeSetup& setup,
                  const BakeSettings& settings, const TileCapacity& cap, bool dry);
  BakeKernelArgs args_;
  size_t device_bytes_ = 0;
  bool radiance_cache_ = false;  // the accumulation group holds the cache's means
  bool guiding_ = false;         // ... and the first-bounce guide's histograms
};

}  // namespace luxel::pipeline
