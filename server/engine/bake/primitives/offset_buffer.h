// The offset buffer of thesis §3.2.1 (Listing 3.1): for paths sorted by
// texel, where each texel's paths start and end, so that accumulation can
// gather over a texel's paths. Launches "offset_fill" (sentinel fill,
// fill_int of kernels/fill.cl) and "offset_generate" (kernels/offset_buffer.cl).
//
// Layout of `offsets` (texel_count + 1 uints), after enqueue:
//   offsets[t]            first path of texel t, when t has paths; the
//                         sentinel 0xFFFFFFFF or the next boundary otherwise
//   offsets[t + 1]        one past the last path of t, when t has paths
//   offsets[texel_count]  number of paths with a valid texel (never the
//                         sentinel)
// Texel t has no paths when offsets[t] or offsets[t + 1] is the sentinel or
// when they are equal (the three rules of §3.2.1). Device code reads it with
// lux_offset_range() from kernels/primitives/offset_buffer.h.
#pragma once

#include <cstdint>
#include <memory>

#include "common/status.h"
#include "device/context.h"

namespace luxel::pipeline {

inline constexpr uint32_t kOffsetSentinel = 0xFFFFFFFFu;

class OffsetBuffer {
 public:
  // texel_count < 0xFFFFFFFF (the sentinel must not be a valid offset end).
  static Result<std::unique_ptr<OffsetBuffer>> create(device::Context& ctx, size_t path_capacity,
                                                      uint32_t texel_count);

  // sorted_texels: texel index of each path, sorted ascending (RadixSort);
  // entries >= texel_count are invalid and must all sit at the end (e.g.
  // 0xFFFFFFFF, which the radix sort puts last). path_count: device int, the
  // live number of paths (clamped on the device to [0, path_capacity]).
  // offsets: texel_count + 1 uints (layout above). active_count_out: device
  // int, the number of paths with a valid texel. Enqueue only.
  Status enqueue(const device::Buffer& sorted_texels, const device::Buffer& path_count,
                 const device::Buffer& offsets, const device::Buffer& active_count_out);

  size_t path_capacity() const { return path_capacity_; }
  uint32_t texel_count() const { return texel_count_; }
  // Entries of the offsets buffer: texel_count + 1.
  size_t offsets_size() const { return size_t{texel_count_} + 1; }

 private:
  OffsetBuffer(device::Context& ctx) : ctx_(ctx) {}

  device::Context& ctx_;
  size_t path_capacity_ = 0;
  uint32_t texel_count_ = 0;
  device::Kernel fill_, generate_;
};

}  // namespace luxel::pipeline
