#include "bake/primitives/radix_sort.h"

#include <algorithm>

namespace luxel::pipeline {
namespace {

constexpr int kDigitBits = 4;  // §2.5: 16 count buckets per pass
constexpr size_t kDigitValues = 16;

}  // namespace

int RadixSort::bits_for(uint32_t max_key) {
  int bits = 0;
  while (bits < 32 && (max_key >> bits) != 0) ++bits;
  return bits;
}

int RadixSort::passes_for(int begin_bit, int end_bit) {
  return end_bit > begin_bit ? (end_bit - begin_bit + kDigitBits - 1) / kDigitBits : 0;
}

Result<std::unique_ptr<RadixSort>> RadixSort::create(device::Context& ctx, size_t capacity,
                                                     TileShape shape) {
  if (capacity > 0x7FFFFFFFu)
    return invalid_argument(
        strprintf("radix sort capacity %zu: counts are ints, at most 2^31-1", capacity));
  std::unique_ptr<RadixSort> sort(new RadixSort(ctx));
  sort->capacity_ = capacity;
  auto built =
      build_tiled_kernels(ctx, "radix_sort.cl",
                          {"radix_histogram", "radix_scan", "radix_scatter", "radix_copy"}, shape);
  if (!built) return built.status();
  sort->shape_ = built->shape;
  sort->histogram_ = std::move(built->kernels[0]);
  sort->scan_ = std::move(built->kernels[1]);
  sort->scatter_ = std::move(built->kernels[2]);
  sort->copy_ = std::move(built->kernels[3]);

  auto keys = ctx.alloc(capacity * sizeof(uint32_t), "radix sort scratch keys");
  if (!keys) return keys.status();
  sort->scratch_keys_ = std::move(keys.value());
  auto values = ctx.alloc(capacity * sizeof(uint32_t), "radix sort scratch values");
  if (!values) return values.status();
  sort->scratch_values_ = std::move(values.value());
  auto table = ctx.alloc(kDigitValues * sort->shape_.groups_for(capacity) * sizeof(uint32_t),
                         "radix sort histogram");
  if (!table) return table.status();
  sort->histogram_table_ = std::move(table.value());
  return sort;
}

size_t RadixSort::device_bytes() const {
  return scratch_keys_.bytes() + scratch_values_.bytes() + histogram_table_.bytes();
}

Status RadixSort::validate(const device::Buffer& keys, const device::Buffer& values,
                           const device::Buffer& count, size_t capacity, int begin_bit,
                           int end_bit) const {
  if (begin_bit < 0 || end_bit > 32 || begin_bit > end_bit)
    return invalid_argument(strprintf("radix sort bit range [%d, %d): need 0 <= begin <= end <= 32",
                                      begin_bit, end_bit));
  if (capacity > capacity_)
    return invalid_argument(
        strprintf("radix sort of %zu keys: the sorter was created for %zu", capacity, capacity_));
  const size_t bytes = capacity * sizeof(uint32_t);
  if (!keys || keys.bytes() < bytes)
    return invalid_argument(strprintf("radix sort keys buffer holds %zu bytes, %zu keys need %zu",
                                      keys.bytes(), capacity, bytes));
  if (values && values.bytes() < bytes)
    return invalid_argument(
        strprintf("radix sort values buffer holds %zu bytes, %zu values need %zu", values.bytes(),
                  capacity, bytes));
  if (values && values.get() == keys.get())
    return invalid_argument("radix sort: keys and values are the same buffer");
  if (!count || count.bytes() < sizeof(int32_t))
    return invalid_argument("radix sort count buffer must hold one int");
  return Status::ok();
}

Status RadixSort::enqueue(const device::Buffer& keys, const device::Buffer& values,
                          const device::Buffer& count, size_t capacity, int begin_bit,
                          int end_bit) {
  LUXEL_RETURN_IF_ERROR(validate(keys, values, count, capacity, begin_bit, end_bit));
  const int passes = passes_for(begin_bit, end_bit);
  if (capacity == 0 || passes == 0) return Status::ok();

  const cl_int with_values = values ? 1 : 0;
  const auto cap = static_cast<cl_uint>(capacity);
  const size_t global = shape_.global_for(capacity);
  const size_t local = shape_.group_size;
  // Ping-pong: even passes read the caller's buffers, odd passes the scratch.
  const device::Buffer* src_keys = &keys;
  const device::Buffer* src_values = &values;
  const device::Buffer* dst_keys = &scratch_keys_;
  const device::Buffer* dst_values = with_values ? &scratch_values_ : &values;
  for (int pass = 0; pass < passes; ++pass) {
    const int shift = begin_bit + pass * kDigitBits;
    const int bits = std::min(kDigitBits, end_bit - shift);
    const auto mask = static_cast<cl_uint>((1u << bits) - 1u);
    const auto ushift = static_cast<cl_uint>(shift);
    LUXEL_RETURN_IF_ERROR(
        histogram_.set_args(*src_keys, count, cap, ushift, mask, histogram_table_));
    LUXEL_RETURN_IF_ERROR(ctx_.launch(histogram_, global, local, "radix_histogram"));
    LUXEL_RETURN_IF_ERROR(scan_.set_args(histogram_table_, count, cap));
    LUXEL_RETURN_IF_ERROR(ctx_.launch(scan_, local, local, "radix_scan"));
    LUXEL_RETURN_IF_ERROR(scatter_.set_args(*src_keys, *src_values, *dst_keys, *dst_values,
                                            with_values, count, cap, ushift, mask,
                                            histogram_table_));
    LUXEL_RETURN_IF_ERROR(ctx_.launch(scatter_, global, local, "radix_scatter"));
    std::swap(src_keys, dst_keys);
    std::swap(src_values, dst_values);
  }
  if (passes % 2 == 1) {
    // The result is in the scratch buffers (src after the last swap).
    LUXEL_RETURN_IF_ERROR(
        copy_.set_args(*src_keys, *src_values, keys, values, with_values, count, cap));
    LUXEL_RETURN_IF_ERROR(ctx_.launch(copy_, global, local, "radix_copy"));
  }
  return Status::ok();
}

}  // namespace luxel::pipeline
