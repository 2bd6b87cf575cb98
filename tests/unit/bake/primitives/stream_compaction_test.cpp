// StreamCompaction on the real OpenCL device against std::copy_if.
#include "bake/primitives/stream_compaction.h"

#include <algorithm>
#include <random>

#include "device_buffers.h"

namespace luxel::pipeline {
namespace {

using testing::random_keys;
using testing::read_back;
using testing::read_count;
using testing::shared_context;
using testing::upload_count;
using testing::upload_rw;

constexpr uint32_t kUntouched = 0xDEADBEEFu;

std::vector<uint32_t> random_flags(size_t n, double p_keep, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::bernoulli_distribution keep(p_keep);
  std::uniform_int_distribution<uint32_t> nonzero(1, 0xFFFFFFFFu);
  std::vector<uint32_t> flags(n);
  // Any non-zero int counts as set, negative ones included.
  for (auto& f : flags) f = keep(rng) ? nonzero(rng) : 0u;
  return flags;
}

struct Compacted {
  std::vector<uint32_t> out;
  int count = -1;
};

// values empty: compact indices. The output buffer starts as kUntouched.
Compacted device_compact(StreamCompaction& c, const std::vector<uint32_t>& values,
                         const std::vector<uint32_t>& flags, int in_count,
                         bool alias_counts = false) {
  auto& ctx = shared_context();
  const size_t capacity = flags.size();
  device::Buffer in = values.empty() ? device::Buffer() : upload_rw(values, "in values");
  device::Buffer flag_buf = upload_rw(flags, "flags");
  device::Buffer out = upload_rw(std::vector<uint32_t>(capacity, kUntouched), "out values");
  device::Buffer in_count_buf = upload_count(in_count, "in count");
  device::Buffer out_count_buf = alias_counts ? device::Buffer() : upload_count(-7, "out count");
  const device::Buffer& out_count = alias_counts ? in_count_buf : out_count_buf;
  const Status st = c.enqueue(in, flag_buf, in_count_buf, out, out_count, capacity);
  EXPECT_TRUE(st.is_ok()) << st.to_string();
  Compacted result{read_back(out, capacity), read_count(out_count)};
  EXPECT_TRUE(ctx.finish().is_ok());
  return result;
}

Compacted reference_compact(const std::vector<uint32_t>& values, const std::vector<uint32_t>& flags,
                            size_t in_count) {
  Compacted r{std::vector<uint32_t>(flags.size(), kUntouched), 0};
  size_t j = 0;
  for (size_t i = 0; i < in_count; ++i)
    if (flags[i] != 0) r.out[j++] = values.empty() ? static_cast<uint32_t>(i) : values[i];
  r.count = static_cast<int>(j);
  return r;
}

void check_compact(StreamCompaction& c, const std::vector<uint32_t>& values,
                   const std::vector<uint32_t>& flags, size_t in_count, bool alias_counts = false) {
  const Compacted want = reference_compact(values, flags, in_count);
  const Compacted got = device_compact(c, values, flags, static_cast<int>(in_count), alias_counts);
  EXPECT_EQ(got.count, want.count);
  const auto at = std::mismatch(got.out.begin(), got.out.end(), want.out.begin());
  EXPECT_TRUE(at.first == got.out.end())
      << "outputs differ first at index " << (at.first - got.out.begin()) << ": device "
      << *at.first << ", reference " << *at.second;
}

std::unique_ptr<StreamCompaction> make_compaction(size_t capacity, TileShape shape = {}) {
  auto c = StreamCompaction::create(shared_context(), capacity, shape);
  EXPECT_TRUE(c.is_ok()) << c.status().to_string();
  return c.is_ok() ? std::move(c.value()) : nullptr;
}

TEST(StreamCompaction, RandomFlagsMatchCopyIf) {
  const size_t n = 10007;
  auto c = make_compaction(n);
  ASSERT_NE(c, nullptr);
  const auto values = random_keys(n, 0xFFFFFFFFu, 21);
  for (double p : {0.02, 0.3, 0.97}) {
    SCOPED_TRACE(p);
    check_compact(*c, values, random_flags(n, p, 22), n);
  }
}

TEST(StreamCompaction, NullValuesWriteTheKeptIndices) {
  const size_t n = 4321;
  auto c = make_compaction(n);
  ASSERT_NE(c, nullptr);
  check_compact(*c, {}, random_flags(n, 0.5, 23), n);
}

TEST(StreamCompaction, NoneAndAllKept) {
  const size_t n = 3000;
  auto c = make_compaction(n);
  ASSERT_NE(c, nullptr);
  const auto values = random_keys(n, 0xFFFFFFFFu, 24);
  check_compact(*c, values, std::vector<uint32_t>(n, 0u), n);
  check_compact(*c, values, std::vector<uint32_t>(n, 1u), n);
}

TEST(StreamCompaction, ZeroAndOneLiveElements) {
  auto c = make_compaction(500);
  ASSERT_NE(c, nullptr);
  const auto values = random_keys(500, 0xFFFFFFFFu, 25);
  const std::vector<uint32_t> all(500, 1u);
  check_compact(*c, values, all, 0);
  check_compact(*c, values, all, 1);
  check_compact(*c, values, std::vector<uint32_t>(500, 0u), 1);
  auto empty = make_compaction(0);
  ASSERT_NE(empty, nullptr);
  device::Buffer flags = upload_rw({1u}, "flags");
  device::Buffer out = upload_rw({kUntouched}, "out");
  device::Buffer count = upload_count(0);
  device::Buffer out_count = upload_count(-1);
  ASSERT_OK(empty->enqueue({}, flags, count, out, out_count, 0));
  EXPECT_EQ(testing::read_count(out_count), 0) << "an empty stream still writes its count";
}

TEST(StreamCompaction, FlagsPastTheLiveCountAreIgnored) {
  const size_t capacity = 5000;
  auto c = make_compaction(capacity);
  ASSERT_NE(c, nullptr);
  const auto values = random_keys(capacity, 0xFFFFFFFFu, 26);
  const auto flags = random_flags(capacity, 0.5, 27);
  for (size_t count : {size_t{1025}, size_t{2999}, size_t{4999}})
    check_compact(*c, values, flags, count);
}

TEST(StreamCompaction, InputAndOutputCountMayBeOneBuffer) {
  const size_t n = 6000;
  auto c = make_compaction(n);
  ASSERT_NE(c, nullptr);
  check_compact(*c, random_keys(n, 0xFFFFFFFFu, 28), random_flags(n, 0.4, 29), 5555,
                /*alias_counts=*/true);
}

TEST(StreamCompaction, TinyTilesAgree) {
  // 4 work-items x 3 elements: tiles of odd size, many tiles.
  auto c = make_compaction(2500, TileShape{4, 3});
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->shape().tile(), 12u);
  check_compact(*c, random_keys(2500, 0xFFFFFFFFu, 30), random_flags(2500, 0.5, 31), 2345);
}

TEST(StreamCompaction, NamesItsLaunches) {
  auto& ctx = shared_context();
  auto c = make_compaction(1000);
  ASSERT_NE(c, nullptr);
  ASSERT_OK(ctx.finish());
  ctx.timer().reset();
  check_compact(*c, {}, random_flags(1000, 0.5, 32), 1000);
  for (const char* name : {"compact_count", "compact_scan", "compact_scatter"})
    EXPECT_EQ(ctx.timer().stats().count(name), 1u) << name;
  ctx.timer().reset();
}

TEST(StreamCompaction, RejectsInPlaceAndShortBuffers) {
  auto c = make_compaction(100);
  ASSERT_NE(c, nullptr);
  device::Buffer values = upload_rw(random_keys(100, 9, 33), "values");
  device::Buffer flags = upload_rw(random_keys(100, 1, 34), "flags");
  device::Buffer small = upload_rw(random_keys(10, 9, 35), "small");
  device::Buffer count = upload_count(100);
  Status st = c->enqueue(values, flags, count, values, count, 100);
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(st.message().find("same buffer"), std::string::npos) << st.to_string();
  st = c->enqueue(values, small, count, values, count, 100);
  EXPECT_NE(st.message().find("flags"), std::string::npos) << st.to_string();
  st = c->enqueue(values, flags, count, small, count, 100);
  EXPECT_NE(st.message().find("output values"), std::string::npos) << st.to_string();
  st = c->enqueue(values, flags, count, small, count, 200);
  EXPECT_NE(st.message().find("created for 100"), std::string::npos) << st.to_string();
}

}  // namespace
}  // namespace luxel::pipeline
