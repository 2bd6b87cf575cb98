// OffsetBuffer (thesis §3.2.1, Listing 3.1) on the real OpenCL device against
// a host reference, read back both raw and through the device-side reader
// lux_offset_range (kernels/primitives/offset_buffer.h).
#include "bake/primitives/offset_buffer.h"

#include <algorithm>
#include <random>

#include "bake/primitives/radix_sort.h"
#include "device/program_cache.h"
#include "device_buffers.h"

namespace luxel::pipeline {
namespace {

using testing::read_back;
using testing::read_count;
using testing::shared_context;
using testing::upload_count;
using testing::upload_rw;

struct Range {
  uint32_t first = 0, end = 0;
  bool operator==(const Range&) const = default;
};

struct Expected {
  std::vector<Range> ranges;  // per texel, (0, 0) when it has no paths
  int active = 0;
};

Expected reference(const std::vector<uint32_t>& sorted, size_t count, uint32_t texel_count) {
  Expected e{std::vector<Range>(texel_count), 0};
  const auto begin = sorted.begin();
  const auto live_end = begin + static_cast<long>(count);
  e.active = static_cast<int>(std::lower_bound(begin, live_end, texel_count) - begin);
  for (uint32_t t = 0; t < texel_count; ++t) {
    const auto [lo, hi] = std::equal_range(begin, live_end, t);
    if (lo != hi)
      e.ranges[t] = {static_cast<uint32_t>(lo - begin), static_cast<uint32_t>(hi - begin)};
  }
  return e;
}

// The three sentinel rules of §3.2.1 on the host.
Range host_read(const std::vector<uint32_t>& offsets, uint32_t t) {
  const uint32_t a = offsets[t], b = offsets[t + 1];
  if (a == kOffsetSentinel || b == kOffsetSentinel || a == b) return {};
  return {a, b};
}

struct DeviceResult {
  std::vector<uint32_t> offsets;
  std::vector<Range> ranges;  // through lux_offset_range
  int active = -1;
};

// Runs the offset buffer (and the device reader) for sorted_texels, of which
// `count` are live; the capacity is sorted_texels.size().
DeviceResult run_device(const std::vector<uint32_t>& sorted_texels, int count,
                        uint32_t texel_count) {
  auto& ctx = shared_context();
  DeviceResult r;
  auto ob = OffsetBuffer::create(ctx, sorted_texels.size(), texel_count);
  EXPECT_TRUE(ob.is_ok()) << ob.status().to_string();
  if (!ob) return r;
  device::Buffer texels = upload_rw(sorted_texels, "sorted texels");
  device::Buffer path_count = upload_count(count, "path count");
  // Garbage first: the fill must reset every entry.
  device::Buffer offsets = upload_rw(std::vector<uint32_t>(texel_count + 1, 12345u), "offsets");
  device::Buffer active = upload_count(-99, "active count");
  Status st = ob.value()->enqueue(texels, path_count, offsets, active);
  EXPECT_TRUE(st.is_ok()) << st.to_string();

  auto program = ctx.programs().get("offset_buffer.cl", {});
  EXPECT_TRUE(program.is_ok()) << program.status().to_string();
  if (!program) return r;
  auto reader = program.value()->kernel("offset_read_ranges");
  EXPECT_TRUE(reader.is_ok()) << reader.status().to_string();
  if (!reader) return r;
  auto ranges = ctx.alloc(size_t{texel_count} * 2 * sizeof(uint32_t), "ranges");
  EXPECT_TRUE(ranges.is_ok());
  if (!ranges) return r;
  EXPECT_TRUE(reader.value().set_args(offsets, texel_count, ranges.value()).is_ok());
  EXPECT_TRUE(ctx.launch(reader.value(), texel_count, 64, "offset_read_ranges").is_ok());

  r.offsets = read_back(offsets, texel_count + 1);
  const auto flat = read_back(ranges.value(), size_t{texel_count} * 2);
  for (uint32_t t = 0; t < texel_count; ++t) r.ranges.push_back({flat[2 * t], flat[2 * t + 1]});
  r.active = read_count(active);
  EXPECT_TRUE(ctx.finish().is_ok());
  return r;
}

void check_offsets(const std::vector<uint32_t>& sorted, size_t count, uint32_t texel_count) {
  const Expected want = reference(sorted, count, texel_count);
  const DeviceResult got = run_device(sorted, static_cast<int>(count), texel_count);
  ASSERT_EQ(got.offsets.size(), size_t{texel_count} + 1);
  EXPECT_EQ(got.active, want.active);
  EXPECT_EQ(got.offsets[texel_count], static_cast<uint32_t>(want.active))
      << "offsets[texel_count] holds the number of valid paths";
  for (uint32_t t = 0; t < texel_count; ++t) {
    const Range& w = want.ranges[t];
    ASSERT_EQ(host_read(got.offsets, t), w) << "texel " << t << " (host reader): offsets "
                                            << got.offsets[t] << ", " << got.offsets[t + 1];
    ASSERT_EQ(got.ranges[t], w) << "texel " << t << " (lux_offset_range)";
    if (w.first != w.end) {
      // Texels with paths store their exact boundaries.
      ASSERT_EQ(got.offsets[t], w.first) << "texel " << t;
      ASSERT_EQ(got.offsets[t + 1], w.end) << "texel " << t;
    }
  }
}

// Paths on a random subset of the texels (gaps), sorted, then `invalid`
// invalid entries (>= texel_count) at the end.
std::vector<uint32_t> sorted_paths(size_t valid, size_t invalid, uint32_t texel_count,
                                   double texel_fraction, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<uint32_t> used;
  std::bernoulli_distribution use(texel_fraction);
  for (uint32_t t = 0; t < texel_count; ++t)
    if (use(rng)) used.push_back(t);
  if (used.empty()) used.push_back(texel_count / 2);
  std::uniform_int_distribution<size_t> pick(0, used.size() - 1);
  std::vector<uint32_t> paths(valid);
  for (auto& p : paths) p = used[pick(rng)];
  std::sort(paths.begin(), paths.end());
  const uint32_t markers[] = {texel_count, texel_count + 5, 0xFFFFFFFEu, 0xFFFFFFFFu};
  std::vector<uint32_t> tail(invalid);
  for (size_t i = 0; i < invalid; ++i) tail[i] = markers[i % 4];
  std::sort(tail.begin(), tail.end());
  paths.insert(paths.end(), tail.begin(), tail.end());
  return paths;
}

TEST(OffsetBuffer, RandomPathsWithGapsAndInvalidTail) {
  for (double fraction : {0.05, 0.4, 1.0}) {
    SCOPED_TRACE(fraction);
    check_offsets(sorted_paths(3000, 211, 1000, fraction, 41), 3211, 1000);
  }
}

TEST(OffsetBuffer, FirstAndLastTexelsAndOnePathPerTexel) {
  std::vector<uint32_t> paths = {0, 0, 0, 3, 3, 7, 9, 9};  // texel 9 = texel_count - 1
  check_offsets(paths, paths.size(), 10);
  paths.push_back(0xFFFFFFFFu);
  check_offsets(paths, paths.size(), 10);
  std::vector<uint32_t> dense(777);
  for (uint32_t i = 0; i < 777; ++i) dense[i] = i;
  check_offsets(dense, dense.size(), 777);
  check_offsets(dense, dense.size(), 5000);  // long gap after the last path
}

TEST(OffsetBuffer, NoValidPaths) {
  check_offsets(std::vector<uint32_t>(300, 0xFFFFFFFFu), 300, 64);
  check_offsets(std::vector<uint32_t>(300, 0xFFFFFFFFu), 0, 64);
  check_offsets({5u}, 0, 64);
}

TEST(OffsetBuffer, OneLivePath) {
  check_offsets({5u, 1u, 0u}, 1, 64);  // entries past the count are not sorted: ignored
  check_offsets({63u}, 1, 64);
  check_offsets({64u}, 1, 64);
  check_offsets({0u}, 1, 1);
}

TEST(OffsetBuffer, EntriesPastTheLiveCountAreIgnored) {
  auto paths = sorted_paths(2000, 0, 500, 0.3, 42);
  // Garbage (small, unsorted texels) past the live count.
  for (size_t i = 1500; i < paths.size(); ++i) paths[i] = static_cast<uint32_t>(i % 7);
  check_offsets(paths, 1500, 500);
}

TEST(OffsetBuffer, AfterTheRadixSortOfRandomTexelKeys) {
  // The bake's order of operations: texel keys with invalid markers ->
  // RadixSort over bits_for(texel_count) -> offset buffer.
  auto& ctx = shared_context();
  const uint32_t texel_count = 3000;
  const size_t n = 20000;
  std::mt19937_64 rng(43);
  std::uniform_int_distribution<uint32_t> texel(0, texel_count - 1);
  std::bernoulli_distribution invalid(0.1);
  std::vector<uint32_t> keys(n);
  for (auto& k : keys) k = invalid(rng) ? 0xFFFFFFFFu : texel(rng) / 3 * 3;  // gaps of 2
  auto sorter = RadixSort::create(ctx, n);
  ASSERT_OK(sorter);
  device::Buffer key_buf = upload_rw(keys, "keys");
  device::Buffer count = upload_count(static_cast<int>(n));
  ASSERT_OK(sorter.value()->enqueue(key_buf, {}, count, n, 0, RadixSort::bits_for(texel_count)));
  const auto sorted = read_back(key_buf, n);
  auto want = keys;
  std::sort(want.begin(), want.end());
  ASSERT_TRUE(sorted == want) << "radix sort of texel keys";
  check_offsets(sorted, n, texel_count);
}

TEST(OffsetBuffer, NamesItsLaunchesAndRejectsShortBuffers) {
  auto& ctx = shared_context();
  ASSERT_OK(ctx.finish());
  ctx.timer().reset();
  check_offsets({1u, 2u}, 2, 4);
  EXPECT_EQ(ctx.timer().stats().count("offset_fill"), 1u);
  EXPECT_EQ(ctx.timer().stats().count("offset_generate"), 1u);
  ctx.timer().reset();

  auto ob = OffsetBuffer::create(ctx, 100, 1000);
  ASSERT_OK(ob);
  device::Buffer texels = upload_rw(std::vector<uint32_t>(100, 0u), "texels");
  device::Buffer offsets = upload_rw(std::vector<uint32_t>(1000, 0u), "offsets");  // one short
  device::Buffer count = upload_count(100);
  device::Buffer active = upload_count(0);
  const Status st = ob.value()->enqueue(texels, count, offsets, active);
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(st.message().find("offsets buffer"), std::string::npos) << st.to_string();
  EXPECT_FALSE(OffsetBuffer::create(ctx, 100, 0xFFFFFFFFu).is_ok());
}

}  // namespace
}  // namespace luxel::pipeline
