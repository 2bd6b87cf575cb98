#include "bake/primitives/stream_compaction.h"

namespace luxel::pipeline {

Result<std::unique_ptr<StreamCompaction>> StreamCompaction::create(device::Context& ctx,
                                                                   size_t capacity,
                                                                   TileShape shape) {
  if (capacity > 0x7FFFFFFFu)
    return invalid_argument(
        strprintf("stream compaction capacity %zu: counts are ints, at most 2^31-1", capacity));
  std::unique_ptr<StreamCompaction> c(new StreamCompaction(ctx));
  c->capacity_ = capacity;
  auto built = build_tiled_kernels(ctx, "compact.cl",
                                   {"compact_count", "compact_scan", "compact_scatter"}, shape);
  if (!built) return built.status();
  c->shape_ = built->shape;
  c->count_ = std::move(built->kernels[0]);
  c->scan_ = std::move(built->kernels[1]);
  c->scatter_ = std::move(built->kernels[2]);
  auto counts =
      ctx.alloc(c->shape_.groups_for(capacity) * sizeof(uint32_t), "stream compaction tile counts");
  if (!counts) return counts.status();
  c->tile_counts_ = std::move(counts.value());
  auto snapshot = ctx.alloc(sizeof(uint32_t), "stream compaction live count");
  if (!snapshot) return snapshot.status();
  c->live_snapshot_ = std::move(snapshot.value());
  return c;
}

Status StreamCompaction::validate(const device::Buffer& in_values, const device::Buffer& flags,
                                  const device::Buffer& in_count, const device::Buffer& out_values,
                                  const device::Buffer& out_count, size_t capacity) const {
  if (capacity > capacity_)
    return invalid_argument(
        strprintf("stream compaction of %zu elements: created for %zu", capacity, capacity_));
  const size_t bytes = capacity * sizeof(uint32_t);
  auto too_small = [&](const device::Buffer& b, const char* name) -> Status {
    if (!b || b.bytes() < bytes)
      return invalid_argument(
          strprintf("stream compaction %s buffer holds %zu bytes, %zu elements need %zu", name,
                    b.bytes(), capacity, bytes));
    return Status::ok();
  };
  if (in_values) LUXEL_RETURN_IF_ERROR(too_small(in_values, "input values"));
  LUXEL_RETURN_IF_ERROR(too_small(flags, "flags"));
  LUXEL_RETURN_IF_ERROR(too_small(out_values, "output values"));
  if (in_values && in_values.get() == out_values.get())
    return invalid_argument(
        "stream compaction: input and output values are the same buffer "
        "(in-place compaction would race)");
  if (!in_count || in_count.bytes() < sizeof(int32_t))
    return invalid_argument("stream compaction input count buffer must hold one int");
  if (!out_count || out_count.bytes() < sizeof(int32_t))
    return invalid_argument("stream compaction output count buffer must hold one int");
  return Status::ok();
}

Status StreamCompaction::enqueue(const device::Buffer& in_values, const device::Buffer& flags,
                                 const device::Buffer& in_count, const device::Buffer& out_values,
                                 const device::Buffer& out_count, size_t capacity) {
  LUXEL_RETURN_IF_ERROR(validate(in_values, flags, in_count, out_values, out_count, capacity));
  const cl_int with_values = in_values ? 1 : 0;
  const auto cap = static_cast<cl_uint>(capacity);
  // At least one work-group even for capacity 0: it writes the snapshot and
  // the scan writes *out_count = 0.
  const size_t global = shape_.global_for(capacity);
  const size_t local = shape_.group_size;
  LUXEL_RETURN_IF_ERROR(count_.set_args(flags, in_count, cap, tile_counts_, live_snapshot_));
  LUXEL_RETURN_IF_ERROR(ctx_.launch(count_, global, local, "compact_count"));
  LUXEL_RETURN_IF_ERROR(scan_.set_args(tile_counts_, live_snapshot_, out_count));
  LUXEL_RETURN_IF_ERROR(ctx_.launch(scan_, local, local, "compact_scan"));
  LUXEL_RETURN_IF_ERROR(
      scatter_.set_args(in_values, with_values, flags, live_snapshot_, tile_counts_, out_values));
  return ctx_.launch(scatter_, global, local, "compact_scatter");
}

}  // namespace luxel::pipeline
