// RadixSort on the real OpenCL device against std::stable_sort.
#include "bake/primitives/radix_sort.h"

#include <algorithm>
#include <numeric>

#include "device_buffers.h"

namespace luxel::pipeline {
namespace {

using testing::random_keys;
using testing::read_back;
using testing::shared_context;
using testing::upload_count;
using testing::upload_rw;

struct Sorted {
  std::vector<uint32_t> keys, values;
};

uint32_t bits_of(uint32_t key, int begin_bit, int end_bit) {
  const int width = end_bit - begin_bit;
  if (width <= 0) return 0;
  const uint32_t shifted = key >> begin_bit;
  return width >= 32 ? shifted : shifted & ((1u << width) - 1u);
}

// std::stable_sort of the first `count` pairs by the bit range; the tail is
// left as it was.
Sorted reference_sort(const std::vector<uint32_t>& keys, const std::vector<uint32_t>& values,
                      size_t count, int begin_bit, int end_bit) {
  std::vector<size_t> order(count);
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return bits_of(keys[a], begin_bit, end_bit) < bits_of(keys[b], begin_bit, end_bit);
  });
  Sorted out{keys, values};
  for (size_t i = 0; i < count; ++i) {
    out.keys[i] = keys[order[i]];
    if (!values.empty()) out.values[i] = values[order[i]];
  }
  return out;
}

// Sorts on the device; buffers hold all of keys (the capacity), `count` live.
Sorted device_sort(RadixSort& sorter, const std::vector<uint32_t>& keys,
                   const std::vector<uint32_t>& values, int count, int begin_bit, int end_bit) {
  auto& ctx = shared_context();
  device::Buffer key_buf = upload_rw(keys, "keys");
  device::Buffer value_buf = values.empty() ? device::Buffer() : upload_rw(values, "values");
  device::Buffer count_buf = upload_count(count);
  const Status st = sorter.enqueue(key_buf, value_buf, count_buf, keys.size(), begin_bit, end_bit);
  EXPECT_TRUE(st.is_ok()) << st.to_string();
  Sorted out{read_back(key_buf, keys.size()), {}};
  if (!values.empty()) out.values = read_back(value_buf, values.size());
  EXPECT_TRUE(ctx.finish().is_ok());
  return out;
}

// First index where a and b differ, or -1.
long first_mismatch(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b) {
  if (a.size() != b.size()) return 0;
  const auto it = std::mismatch(a.begin(), a.end(), b.begin());
  return it.first == a.end() ? -1 : static_cast<long>(it.first - a.begin());
}

#define EXPECT_SAME_ARRAY(actual, expected, what)                                              \
  do {                                                                                         \
    const long _at = first_mismatch(actual, expected);                                         \
    EXPECT_EQ(_at, -1) << what << " differ first at index " << _at << ": device "              \
                       << (_at >= 0 && size_t(_at) < (actual).size() ? (actual)[_at] : 0)      \
                       << ", reference "                                                       \
                       << (_at >= 0 && size_t(_at) < (expected).size() ? (expected)[_at] : 0); \
  } while (0)

std::vector<uint32_t> iota_values(size_t n) {
  std::vector<uint32_t> v(n);
  std::iota(v.begin(), v.end(), 0u);
  return v;
}

std::unique_ptr<RadixSort> make_sorter(size_t capacity, TileShape shape = {}) {
  auto sorter = RadixSort::create(shared_context(), capacity, shape);
  EXPECT_TRUE(sorter.is_ok()) << sorter.status().to_string();
  return sorter.is_ok() ? std::move(sorter.value()) : nullptr;
}

// Device vs reference for one input, with values = original positions so
// that any reordering of equal keys shows as a value mismatch.
void check_sort(RadixSort& sorter, const std::vector<uint32_t>& keys, size_t count, int begin_bit,
                int end_bit, bool with_values = true) {
  const std::vector<uint32_t> values =
      with_values ? iota_values(keys.size()) : std::vector<uint32_t>{};
  const Sorted want = reference_sort(keys, values, count, begin_bit, end_bit);
  const Sorted got = device_sort(sorter, keys, values, static_cast<int>(count), begin_bit, end_bit);
  EXPECT_SAME_ARRAY(got.keys, want.keys, "keys");
  if (with_values) EXPECT_SAME_ARRAY(got.values, want.values, "values (stability)");
}

TEST(RadixSort, BitsForCoversTheKeyRange) {
  EXPECT_EQ(RadixSort::bits_for(0), 0);
  EXPECT_EQ(RadixSort::bits_for(1), 1);
  EXPECT_EQ(RadixSort::bits_for(255), 8);
  EXPECT_EQ(RadixSort::bits_for(256), 9);
  EXPECT_EQ(RadixSort::bits_for(511), 9);
  EXPECT_EQ(RadixSort::bits_for(0x7FFFFFFFu), 31);
  EXPECT_EQ(RadixSort::bits_for(0xFFFFFFFFu), 32);
  EXPECT_EQ(RadixSort::passes_for(0, 9), 3);  // §5.3: keys below 512 need three passes
  EXPECT_EQ(RadixSort::passes_for(29, 32), 1);
  EXPECT_EQ(RadixSort::passes_for(0, 32), 8);
  EXPECT_EQ(RadixSort::passes_for(7, 7), 0);
}

TEST(RadixSort, RandomKeysAndValuesAllBits) {
  auto sorter = make_sorter(10007);
  ASSERT_NE(sorter, nullptr);
  const auto keys = random_keys(10007, 0xFFFFFFFFu, 1);
  check_sort(*sorter, keys, keys.size(), 0, 32);
}

TEST(RadixSort, RandomKeysOnlyWithManyDuplicates) {
  auto sorter = make_sorter(7777);
  ASSERT_NE(sorter, nullptr);
  const auto keys = random_keys(7777, 40, 2);
  check_sort(*sorter, keys, keys.size(), 0, RadixSort::bits_for(40), /*with_values=*/false);
  check_sort(*sorter, keys, keys.size(), 0, RadixSort::bits_for(40));
}

TEST(RadixSort, AdversarialOrders) {
  const size_t n = 5000;
  auto sorter = make_sorter(n);
  ASSERT_NE(sorter, nullptr);
  const std::vector<uint32_t> equal(n, 0xABCDu);
  check_sort(*sorter, equal, n, 0, 16);
  std::vector<uint32_t> ascending(n), descending(n);
  for (size_t i = 0; i < n; ++i) {
    ascending[i] = static_cast<uint32_t>(i * 3);
    descending[i] = static_cast<uint32_t>((n - i) * 3);
  }
  check_sort(*sorter, ascending, n, 0, 32);
  check_sort(*sorter, descending, n, 0, 32);
  // Sorted but only by the top bits: stability inside equal digits matters.
  std::vector<uint32_t> pairs(n);
  for (size_t i = 0; i < n; ++i) pairs[i] = static_cast<uint32_t>((n - i) / 7);
  check_sort(*sorter, pairs, n, 0, 16);
}

TEST(RadixSort, ExtremeKeysWithThirtyTwoBits) {
  auto sorter = make_sorter(3001);
  ASSERT_NE(sorter, nullptr);
  auto keys = random_keys(3001, 0xFFFFFFFFu, 3);
  for (size_t i = 0; i < keys.size(); i += 5) keys[i] = 0xFFFFFFFFu;
  for (size_t i = 2; i < keys.size(); i += 11) keys[i] = 0;
  for (size_t i = 3; i < keys.size(); i += 13) keys[i] = 0x80000000u;
  check_sort(*sorter, keys, keys.size(), 0, 32);
}

TEST(RadixSort, ZeroAndOneLiveElementsChangeNothing) {
  auto sorter = make_sorter(300);
  ASSERT_NE(sorter, nullptr);
  const auto keys = random_keys(300, 0xFFFFFFFFu, 4);
  check_sort(*sorter, keys, 0, 0, 32);
  check_sort(*sorter, keys, 1, 0, 32);
  check_sort(*sorter, keys, 2, 0, 32);
  // A one-element buffer and an empty sorter.
  auto tiny = make_sorter(1);
  ASSERT_NE(tiny, nullptr);
  check_sort(*tiny, {42u}, 1, 0, 32);
  auto empty = make_sorter(0);
  ASSERT_NE(empty, nullptr);
  device::Buffer keys_buf = upload_rw({7u}, "keys");
  device::Buffer count = upload_count(0);
  ASSERT_OK(empty->enqueue(keys_buf, {}, count, 0, 0, 32));
}

TEST(RadixSort, CountBelowCapacityLeavesTheTailUntouched) {
  const size_t capacity = 6000;
  auto sorter = make_sorter(capacity);
  ASSERT_NE(sorter, nullptr);
  auto keys = random_keys(capacity, 4095, 5);
  // Odd pass count (12 bits = 3 passes) exercises the copy back, even (16
  // bits) the plain ping-pong; counts not a multiple of any tile size.
  for (size_t count : {size_t{3001}, size_t{4097}, size_t{5999}}) {
    check_sort(*sorter, keys, count, 0, 12);
    check_sort(*sorter, keys, count, 0, 16);
  }
}

TEST(RadixSort, CountAboveCapacityIsClamped) {
  auto sorter = make_sorter(1000);
  ASSERT_NE(sorter, nullptr);
  const auto keys = random_keys(1000, 0xFFFFu, 6);
  const std::vector<uint32_t> values = iota_values(keys.size());
  const Sorted want = reference_sort(keys, values, keys.size(), 0, 16);
  const Sorted got = device_sort(*sorter, keys, values, 1 << 20, 0, 16);
  EXPECT_SAME_ARRAY(got.keys, want.keys, "keys");
  EXPECT_SAME_ARRAY(got.values, want.values, "values");
}

TEST(RadixSort, TopThreeBitsOnlyKeepRayOrderInsideOctants) {
  // §5.4: key = octant << 29 | ray index, sorted by bits [29, 32) only.
  const size_t n = 9000;
  auto sorter = make_sorter(n);
  ASSERT_NE(sorter, nullptr);
  const auto octants = random_keys(n, 7, 7);
  std::vector<uint32_t> keys(n);
  for (size_t i = 0; i < n; ++i) keys[i] = octants[i] << 29 | static_cast<uint32_t>(i);
  check_sort(*sorter, keys, n, 29, 32, /*with_values=*/false);
  const Sorted got = device_sort(*sorter, keys, {}, static_cast<int>(n), 29, 32);
  for (size_t i = 1; i < n; ++i) {
    const uint32_t a = got.keys[i - 1], b = got.keys[i];
    ASSERT_TRUE((a >> 29) < (b >> 29) || ((a >> 29) == (b >> 29) && a < b))
        << "at " << i << ": octants " << (a >> 29) << ", " << (b >> 29) << " rays "
        << (a & 0x1FFFFFFFu) << ", " << (b & 0x1FFFFFFFu);
  }
}

TEST(RadixSort, BitRangesNotAlignedToDigits) {
  auto sorter = make_sorter(4000);
  ASSERT_NE(sorter, nullptr);
  const auto keys = random_keys(4000, 0xFFFFFFFFu, 8);
  check_sort(*sorter, keys, keys.size(), 5, 18);  // 4 passes, last one 1 bit
  check_sort(*sorter, keys, keys.size(), 3, 6);   // 1 pass of 3 bits
  check_sort(*sorter, keys, keys.size(), 1, 32);  // 8 passes, last 3 bits
  check_sort(*sorter, keys, keys.size(), 9, 9);   // nothing to do
}

TEST(RadixSort, InvalidTexelMarkersSortToTheEndWithTheTexelBitRange) {
  const uint32_t texel_count = 1000;  // bits_for(1000) = 10; 0xFFFFFFFF masks to 1023
  auto sorter = make_sorter(5000);
  ASSERT_NE(sorter, nullptr);
  auto keys = random_keys(5000, texel_count - 1, 9);
  for (size_t i = 0; i < keys.size(); i += 3) keys[i] = 0xFFFFFFFFu;
  const Sorted got =
      device_sort(*sorter, keys, iota_values(keys.size()), static_cast<int>(keys.size()), 0,
                  RadixSort::bits_for(texel_count));
  auto want = keys;
  std::stable_sort(want.begin(), want.end());
  EXPECT_SAME_ARRAY(got.keys, want, "keys");
}

TEST(RadixSort, TinyTilesWithTheOtherScatterAgree) {
  // 4 work-items x 3 keys: fewer work-items than digits, tiles of odd size,
  // many tiles, multi-entry chunks in the one-group scan; and the scatter
  // variant the device does not use by default (local reorder on CPUs,
  // direct writes on GPUs), so both are checked on every device.
  TileShape shape{4, 3, !preferred_tile_shape(shared_context().info()).local_reorder};
  SCOPED_TRACE(shape.describe());
  auto sorter = make_sorter(3333, shape);
  ASSERT_NE(sorter, nullptr);
  EXPECT_EQ(sorter->shape().tile(), shape.tile());
  const auto keys = random_keys(3333, 0xFFFFFu, 10);
  check_sort(*sorter, keys, keys.size(), 0, 20);
  check_sort(*sorter, keys, 1234, 0, 7);
  check_sort(*sorter, keys, 3000, 29, 32, /*with_values=*/false);
}

TEST(RadixSort, RunsOnlyThePassesTheBitRangeNeedsUnderTheirNames) {
  auto& ctx = shared_context();
  auto sorter = make_sorter(2048);
  ASSERT_NE(sorter, nullptr);
  const auto keys = random_keys(2048, 511, 11);
  ASSERT_OK(ctx.finish());
  ctx.timer().reset();
  check_sort(*sorter, keys, keys.size(), 0, RadixSort::bits_for(511));
  const auto& stats = ctx.timer().stats();
  ASSERT_TRUE(stats.count("radix_histogram") && stats.count("radix_scan") &&
              stats.count("radix_scatter") && stats.count("radix_copy"));
  EXPECT_EQ(stats.at("radix_histogram").launches, 3u);
  EXPECT_EQ(stats.at("radix_scan").launches, 3u);
  EXPECT_EQ(stats.at("radix_scatter").launches, 3u);
  EXPECT_EQ(stats.at("radix_copy").launches, 1u);
  ctx.timer().reset();
}

TEST(RadixSort, RejectsBadArgumentsNamingThem) {
  auto sorter = make_sorter(100);
  ASSERT_NE(sorter, nullptr);
  device::Buffer keys = upload_rw(random_keys(100, 9, 12), "keys");
  device::Buffer small = upload_rw(random_keys(10, 9, 13), "small values");
  device::Buffer count = upload_count(100);
  auto code_and_message = [](const Status& st, const char* word) {
    EXPECT_EQ(st.code(), StatusCode::kInvalidArgument) << st.to_string();
    EXPECT_NE(st.message().find(word), std::string::npos) << st.to_string();
  };
  code_and_message(sorter->enqueue(keys, {}, count, 100, 4, 2), "bit range");
  code_and_message(sorter->enqueue(keys, {}, count, 100, 0, 33), "bit range");
  code_and_message(sorter->enqueue(keys, {}, count, 101, 0, 32), "created for 100");
  code_and_message(sorter->enqueue(keys, small, count, 100, 0, 32), "values");
  code_and_message(sorter->enqueue(keys, keys, count, 100, 0, 32), "same buffer");
  code_and_message(sorter->enqueue(keys, {}, {}, 100, 0, 32), "count");
}

}  // namespace
}  // namespace luxel::pipeline
