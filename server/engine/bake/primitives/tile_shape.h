// How the primitives' kernels tile their input: work-group size and elements
// per work-item, chosen per device and baked into the program as build
// options (kernels/primitives/tile.h).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "common/status.h"
#include "device/context.h"

namespace luxel::pipeline {

struct TileShape {
  size_t group_size = 0;      // work-items per work-group, a power of two
  size_t items_per_item = 0;  // elements each work-item owns in one tile
  // Reorder a tile in local memory before scattering it (coalesced stores on
  // GPUs); off, each work-item writes its run directly (better on CPUs).
  bool local_reorder = false;

  size_t tile() const { return group_size * items_per_item; }
  // Work-groups to launch so that `capacity` elements are covered (at least 1).
  size_t groups_for(size_t capacity) const;
  // Work-items to launch for `capacity` elements.
  size_t global_for(size_t capacity) const { return groups_for(capacity) * group_size; }
  bool valid() const;
  std::string describe() const;  // "128x8, local reorder"
};

// The shape the primitives start from on this device: 128 work-items x 8
// with local reordering on GPUs (about 17 KiB of local memory for the radix
// scatter, so several work-groups fit per compute unit); 1 x 4096 without on
// CPUs (PoCL runs a work-group as a loop on one core: one work-item per tile
// makes each tile a plain serial counting sort with no barrier or local scan
// cost; 2-4x faster than 16 x 64 or 64 x 16 in tests/bench/sort.cpp).
TileShape preferred_tile_shape(const device::DeviceInfo& device);

// A program of kernels/<entry> built for one tile shape.
struct TiledKernels {
  TileShape shape;
  std::vector<device::Kernel> kernels;  // in the order of the names asked for
};

// Builds kernels/<entry> with -DLUX_PRIM_WG/-DLUX_PRIM_ITEMS (and
// -DLUX_PRIM_LOCAL_REORDER) from `shape`
// (preferred_tile_shape() when shape.group_size is 0), halving the
// work-group size while the driver reports that a kernel cannot run with it
// (CL_KERNEL_WORK_GROUP_SIZE, local memory).
Result<TiledKernels> build_tiled_kernels(device::Context& ctx, const std::string& entry,
                                         const std::vector<std::string>& kernel_names,
                                         TileShape shape);

}  // namespace luxel::pipeline
