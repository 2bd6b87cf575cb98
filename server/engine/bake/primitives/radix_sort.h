// Stable LSD radix sort on the OpenCL device (thesis §2.5, §5.3): uint keys,
// optionally carrying one 32-bit value per key, 4-bit digits, three launches
// per digit ("radix_histogram", "radix_scan", "radix_scatter") and one
// "radix_copy" when the number of passes is odd. Kernels: kernels/radix_sort.cl.
//
// Uses in the bake:
//  - texel sorting (§3.2.1): keys = texel indices, invalid paths 0xFFFFFFFF;
//    sort bits [0, bits_for(texel_count)). The invalid marker's low bits are
//    then all ones, i.e. >= texel_count, so invalid keys land at the end in
//    that bit range too (and keep their full value 0xFFFFFFFF).
//  - ray-direction sorting (§5.4): key = octant << 29 | ray index, sort only
//    bits [29, 32): one pass, and stability keeps ray order inside an octant.
#pragma once

#include <cstdint>
#include <memory>

#include "bake/primitives/tile_shape.h"
#include "common/status.h"
#include "device/context.h"

namespace luxel::pipeline {

class RadixSort {
 public:
  // Allocates the scratch buffers for up to `capacity` keys and values
  // (values scratch is always allocated, so enqueue never allocates) and
  // builds the kernels. `shape` overrides the device's tile shape (tests,
  // benchmarks); the default picks preferred_tile_shape().
  static Result<std::unique_ptr<RadixSort>> create(device::Context& ctx, size_t capacity,
                                                   TileShape shape = {});

  // Stable sort of keys[0 .. *count) by bits [begin_bit, end_bit) of the key,
  // permuting values[0 .. *count) alike when `values` is a non-null buffer
  // (a null Buffer sorts keys only). `count` is a device buffer holding one
  // int, the live count, clamped on the device to [0, capacity]. The result
  // ends in keys/values; elements at and past *count are not touched.
  // ceil((end_bit - begin_bit) / 4) passes; 0 <= begin_bit <= end_bit <= 32.
  // `capacity` (<= the created capacity) sizes the launch grids. Enqueue
  // only: no host synchronisation, no read-back. keys and values must be
  // different buffers, each of at least capacity * 4 bytes.
  Status enqueue(const device::Buffer& keys, const device::Buffer& values,
                 const device::Buffer& count, size_t capacity, int begin_bit, int end_bit);

  // Smallest bit count that covers max_key (0 for 0, 32 for 0xFFFFFFFF): sort
  // bits [0, bits_for(max_key)) to do only as many passes as the range needs.
  static int bits_for(uint32_t max_key);
  // Passes enqueue() runs for a bit range (4-bit digits).
  static int passes_for(int begin_bit, int end_bit);

  size_t capacity() const { return capacity_; }
  const TileShape& shape() const { return shape_; }
  // Bytes of device memory this sorter owns (scratch keys, values, histogram).
  size_t device_bytes() const;

 private:
  RadixSort(device::Context& ctx) : ctx_(ctx) {}
  Status validate(const device::Buffer& keys, const device::Buffer& values,
                  const device::Buffer& count, size_t capacity, int begin_bit, int end_bit) const;

  device::Context& ctx_;
  size_t capacity_ = 0;
  TileShape shape_;
  device::Kernel histogram_, scan_, scatter_, copy_;
  device::Buffer scratch_keys_, scratch_values_, histogram_table_;
};

}  // namespace luxel::pipeline
