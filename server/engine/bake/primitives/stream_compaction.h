// Stream compaction on the OpenCL device (thesis §5.1, after Wald [53]):
// keeps the live elements whose flag is set, in order, and writes how many
// were kept to a device int. Launches "compact_count", "compact_scan",
// "compact_scatter"; kernels/compact.cl.
#pragma once

#include <cstdint>
#include <memory>

#include "bake/primitives/tile_shape.h"
#include "common/status.h"
#include "device/context.h"

namespace luxel::pipeline {

class StreamCompaction {
 public:
  // Allocates the per-tile table for up to `capacity` elements and builds the
  // kernels. `shape` overrides the device's tile shape (tests, benchmarks).
  static Result<std::unique_ptr<StreamCompaction>> create(device::Context& ctx, size_t capacity,
                                                          TileShape shape = {});

  // For each i < *in_count (in order) with flags[i] != 0:
  //   out_values[j++] = in_values[i]   (32-bit elements)
  //   out_values[j++] = i              when in_values is a null Buffer (the
  //                                    index buffer of active paths, §5.1)
  // then *out_count = j. Entries of out_values at and past j are not touched.
  // in_count / out_count: device buffers of one int; *in_count is clamped on
  // the device to [0, capacity]. in_count and out_count MAY be the same
  // buffer (the live count is snapshotted before it is overwritten);
  // in_values and out_values must NOT be the same buffer (tiles run
  // concurrently, an in-place compaction would race). flags: one int per
  // element. Buffers hold at least capacity elements; `capacity` (<= the
  // created capacity) sizes the launch grids. Enqueue only.
  Status enqueue(const device::Buffer& in_values, const device::Buffer& flags,
                 const device::Buffer& in_count, const device::Buffer& out_values,
                 const device::Buffer& out_count, size_t capacity);

  size_t capacity() const { return capacity_; }
  const TileShape& shape() const { return shape_; }
  size_t device_bytes() const { return tile_counts_.bytes() + live_snapshot_.bytes(); }

 private:
  StreamCompaction(device::Context& ctx) : ctx_(ctx) {}
  Status validate(const device::Buffer& in_values, const device::Buffer& flags,
                  const device::Buffer& in_count, const device::Buffer& out_values,
                  const device::Buffer& out_count, size_t capacity) const;

  device::Context& ctx_;
  size_t capacity_ = 0;
  TileShape shape_;
  device::Kernel count_, scan_, scatter_;
  device::Buffer tile_counts_, live_snapshot_;
};

}  // namespace luxel::pipeline
