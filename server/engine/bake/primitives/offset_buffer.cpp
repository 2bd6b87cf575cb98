#include "bake/primitives/offset_buffer.h"

#include <algorithm>

#include "device/program_cache.h"

namespace luxel::pipeline {
namespace {

// fill_int and offset_generate are plain one-item-per-element kernels.
constexpr size_t kGroupSize = 64;

}  // namespace

Result<std::unique_ptr<OffsetBuffer>> OffsetBuffer::create(device::Context& ctx,
                                                           size_t path_capacity,
                                                           uint32_t texel_count) {
  if (texel_count >= 0x7FFFFFFFu)
    return invalid_argument(
        strprintf("offset buffer for %u texels: at most 2^31-2 texels "
                  "(the fill kernel counts in ints)",
                  texel_count));
  if (path_capacity >= kOffsetSentinel)
    return invalid_argument(
        strprintf("offset buffer for %zu paths: path offsets must stay below "
                  "the sentinel 0xFFFFFFFF",
                  path_capacity));
  std::unique_ptr<OffsetBuffer> ob(new OffsetBuffer(ctx));
  ob->path_capacity_ = path_capacity;
  ob->texel_count_ = texel_count;
  auto fill = ctx.programs().get("fill.cl", {});
  if (!fill) return fill.status();
  auto fill_kernel = fill.value()->kernel("fill_int");
  if (!fill_kernel) return fill_kernel.status();
  ob->fill_ = std::move(fill_kernel.value());
  auto program = ctx.programs().get("offset_buffer.cl", {});
  if (!program) return program.status();
  auto generate = program.value()->kernel("offset_generate");
  if (!generate) return generate.status();
  ob->generate_ = std::move(generate.value());
  return ob;
}

Status OffsetBuffer::enqueue(const device::Buffer& sorted_texels, const device::Buffer& path_count,
                             const device::Buffer& offsets,
                             const device::Buffer& active_count_out) {
  if (!sorted_texels || sorted_texels.bytes() < path_capacity_ * sizeof(uint32_t))
    return invalid_argument(
        strprintf("offset buffer: sorted texels buffer holds %zu bytes, %zu paths need %zu",
                  sorted_texels.bytes(), path_capacity_, path_capacity_ * sizeof(uint32_t)));
  if (!offsets || offsets.bytes() < offsets_size() * sizeof(uint32_t))
    return invalid_argument(
        strprintf("offset buffer: offsets buffer holds %zu bytes, %u texels need %zu",
                  offsets.bytes(), texel_count_, offsets_size() * sizeof(uint32_t)));
  if (!path_count || path_count.bytes() < sizeof(int32_t))
    return invalid_argument("offset buffer: path count buffer must hold one int");
  if (!active_count_out || active_count_out.bytes() < sizeof(int32_t))
    return invalid_argument("offset buffer: active count buffer must hold one int");

  const auto entries = static_cast<cl_int>(offsets_size());
  LUXEL_RETURN_IF_ERROR(fill_.set_args(offsets, static_cast<cl_int>(kOffsetSentinel), entries));
  LUXEL_RETURN_IF_ERROR(ctx_.launch(fill_, offsets_size(), kGroupSize, "offset_fill"));
  LUXEL_RETURN_IF_ERROR(generate_.set_args(sorted_texels, path_count,
                                           static_cast<cl_uint>(path_capacity_), texel_count_,
                                           offsets, active_count_out));
  // At least one work-item: it writes the empty result when no path is live.
  return ctx_.launch(generate_, std::max<size_t>(path_capacity_, 1), kGroupSize, "offset_generate");
}

}  // namespace luxel::pipeline
