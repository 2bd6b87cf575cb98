// tests/bench/sort: throughput of the data-parallel primitives on the OpenCL
// device (PoCL on a CPU-only machine) against the C++ standard library on the
// same keys, in one run. Prints markdown tables for docs/performance.md.
//
//   bench_sort [--min-log A] [--max-log B] [--step S] [--repeats R] [--device SPEC]
//              [--work-group W --items I [--local-reorder]]
//   sizes 2^A, 2^(A+S), ... 2^B (default 16..22 step 2), best of R runs each.
//
// OpenCL times are kernel times from the context's launch timer (profiling
// events; uploads are not counted); host times are wall time of one thread.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "bake/primitives/radix_sort.h"
#include "bake/primitives/stream_compaction.h"
#include "common/machine_info.h"
#include "device/context.h"

using namespace luxel;

namespace {

int fail(const Status& st) {
  std::fprintf(stderr, "bench_sort: %s\n", st.to_string().c_str());
  return 1;
}

template <typename F>
double best_wall_ms(int repeats, F&& run) {
  double best = 1e300;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    run();
    const auto t1 = std::chrono::steady_clock::now();
    best = std::min(best, std::chrono::duration<double, std::milli>(t1 - t0).count());
  }
  return best;
}

// Best kernel time of `enqueue` over `repeats` runs; `prepare` (untimed)
// restores the inputs before each run.
template <typename P, typename E>
Result<double> best_device_ms(device::Context& ctx, int repeats, P&& prepare, E&& enqueue) {
  double best = 1e300;
  for (int r = 0; r < repeats; ++r) {
    LUXEL_RETURN_IF_ERROR(prepare());
    LUXEL_RETURN_IF_ERROR(ctx.finish());
    ctx.timer().reset();
    LUXEL_RETURN_IF_ERROR(enqueue());
    LUXEL_RETURN_IF_ERROR(ctx.finish());
    best = std::min(best, ctx.timer().total_ms());
  }
  return best;
}

double mkeys(size_t n, double ms) {
  return ms > 0 ? static_cast<double>(n) / (ms * 1e3) : 0.0;
}

struct Options {
  int min_log = 16, max_log = 22, step = 2, repeats = 3;
  std::string device;
  pipeline::TileShape shape;
};

Status bench_sort(device::Context& ctx, const Options& o) {
  std::printf(
      "| keys | key bits | OpenCL keys Mkeys/s | OpenCL key+value Mkeys/s | std::sort Mkeys/s "
      "| std::stable_sort Mkeys/s | OpenCL / std::sort |\n");
  std::printf("|---:|---:|---:|---:|---:|---:|---:|\n");
  std::string last_table;
  int last_log = o.min_log;
  for (int log = o.min_log; log <= o.max_log; log += o.step) {
    const size_t n = size_t{1} << log;
    auto sorter = pipeline::RadixSort::create(ctx, n, o.shape);
    if (!sorter) return sorter.status();
    auto keys_buf = ctx.alloc(n * 4, "bench keys");
    if (!keys_buf) return keys_buf.status();
    auto values_buf = ctx.alloc(n * 4, "bench values");
    if (!values_buf) return values_buf.status();
    const int count = static_cast<int>(n);
    auto count_buf = ctx.upload_bytes(&count, sizeof count, "bench count");
    if (!count_buf) return count_buf.status();
    std::vector<uint32_t> indices(n);
    std::iota(indices.begin(), indices.end(), 0u);

    // 16- and 32-bit keys sorted on all their bits, and the ray-direction
    // sort of §5.4 (octant << 29 | ray index, bits [29, 32): one pass).
    struct Case {
      uint32_t max_key;
      int begin_bit, end_bit;
      const char* label;
    };
    for (const Case& c : {Case{0xFFFFu, 0, 16, "16"}, Case{0xFFFFFFFFu, 0, 32, "32"},
                          Case{0xFFFFFFFFu, 29, 32, "29..31 (rays)"}}) {
      std::mt19937_64 rng(1234 + static_cast<uint64_t>(log) * 7 +
                          static_cast<uint64_t>(c.end_bit - c.begin_bit));
      std::uniform_int_distribution<uint32_t> dist(0, c.max_key);
      std::vector<uint32_t> keys(n);
      for (auto& k : keys) k = dist(rng);

      auto upload_keys = [&] { return ctx.write(keys_buf.value(), keys.data(), n * 4); };
      auto keys_only = best_device_ms(ctx, o.repeats, upload_keys, [&] {
        return sorter.value()->enqueue(keys_buf.value(), {}, count_buf.value(), n, c.begin_bit,
                                       c.end_bit);
      });
      if (!keys_only) return keys_only.status();
      std::vector<uint32_t> sorted(n);
      LUXEL_RETURN_IF_ERROR(ctx.read(keys_buf.value(), sorted));
      auto with_values = best_device_ms(
          ctx, o.repeats,
          [&] {
            LUXEL_RETURN_IF_ERROR(upload_keys());
            return ctx.write(values_buf.value(), indices.data(), n * 4);
          },
          [&] {
            return sorter.value()->enqueue(keys_buf.value(), values_buf.value(), count_buf.value(),
                                           n, c.begin_bit, c.end_bit);
          });
      if (!with_values) return with_values.status();
      if (c.end_bit - c.begin_bit == 32) {
        last_table = ctx.timer().table();
        last_log = log;
      }

      // The host sorts compare on the same bits (the copy of the input is
      // inside the timed region; it is < 1% of a sort).
      auto less = [&](uint32_t a, uint32_t b) { return a >> c.begin_bit < b >> c.begin_bit; };
      std::vector<uint32_t> work;
      const double sort_ms = best_wall_ms(o.repeats, [&] {
        work = keys;
        std::sort(work.begin(), work.end(), less);
      });
      const double stable_ms = best_wall_ms(o.repeats, [&] {
        work = keys;
        std::stable_sort(work.begin(), work.end(), less);
      });
      if (work != sorted)
        return internal_error(strprintf(
            "radix sort of %zu keys on bits %s disagrees with std::stable_sort", n, c.label));
      std::printf("| 2^%d | %s | %.1f | %.1f | %.1f | %.1f | %.2f |\n", log, c.label,
                  mkeys(n, keys_only.value()), mkeys(n, with_values.value()), mkeys(n, sort_ms),
                  mkeys(n, stable_ms), sort_ms / keys_only.value());
      std::fflush(stdout);
    }
  }
  std::printf("\nper-kernel times of the last key+value sort (2^%d keys, 32 bits):\n%s\n", last_log,
              last_table.c_str());
  return Status::ok();
}

Status bench_compaction(device::Context& ctx, const Options& o) {
  std::printf(
      "| elements | kept | OpenCL Melem/s | std::copy_if Melem/s |\n|---:|---:|---:|---:|\n");
  for (int log = o.min_log; log <= o.max_log; log += o.step) {
    const size_t n = size_t{1} << log;
    auto compaction = pipeline::StreamCompaction::create(ctx, n, o.shape);
    if (!compaction) return compaction.status();
    std::mt19937_64 rng(99 + static_cast<uint64_t>(log));
    std::bernoulli_distribution keep(0.5);
    std::vector<uint32_t> values(n), flags(n);
    for (size_t i = 0; i < n; ++i) {
      values[i] = static_cast<uint32_t>(rng());
      flags[i] = keep(rng) ? 1u : 0u;
    }
    auto in = ctx.upload(values, "bench in", CL_MEM_READ_WRITE);
    if (!in) return in.status();
    auto flag_buf = ctx.upload(flags, "bench flags", CL_MEM_READ_WRITE);
    if (!flag_buf) return flag_buf.status();
    auto out = ctx.alloc(n * 4, "bench out");
    if (!out) return out.status();
    const int count = static_cast<int>(n);
    auto count_buf = ctx.upload_bytes(&count, sizeof count, "bench count");
    if (!count_buf) return count_buf.status();
    auto out_count = ctx.alloc(sizeof(int), "bench out count");
    if (!out_count) return out_count.status();
    auto ms = best_device_ms(
        ctx, o.repeats, [] { return Status::ok(); },
        [&] {
          return compaction.value()->enqueue(in.value(), flag_buf.value(), count_buf.value(),
                                             out.value(), out_count.value(), n);
        });
    if (!ms) return ms.status();
    int kept = 0;
    LUXEL_RETURN_IF_ERROR(ctx.read(out_count.value(), &kept, sizeof kept));
    std::vector<uint32_t> host_out(n);
    size_t host_kept = 0;
    const double host_ms = best_wall_ms(o.repeats, [&] {
      size_t j = 0;
      for (size_t i = 0; i < n; ++i)
        if (flags[i] != 0) host_out[j++] = values[i];
      host_kept = j;
    });
    std::vector<uint32_t> device_out(n);
    LUXEL_RETURN_IF_ERROR(ctx.read(out.value(), device_out));
    // Comparing also keeps the host loop's stores alive (no dead-store elision).
    if (static_cast<size_t>(kept) != host_kept ||
        !std::equal(host_out.begin(), host_out.begin() + static_cast<long>(host_kept),
                    device_out.begin()))
      return internal_error(
          strprintf("compaction of %zu elements: device kept %d, host %zu, or they differ", n, kept,
                    host_kept));
    std::printf("| 2^%d | %d | %.1f | %.1f |\n", log, kept, mkeys(n, ms.value()),
                mkeys(n, host_ms));
    std::fflush(stdout);
  }
  return Status::ok();
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next_int = [&] { return std::atoi(argv[++i]); };
    if (a == "--min-log" && i + 1 < argc)
      o.min_log = next_int();
    else if (a == "--max-log" && i + 1 < argc)
      o.max_log = next_int();
    else if (a == "--step" && i + 1 < argc)
      o.step = std::max(1, next_int());
    else if (a == "--repeats" && i + 1 < argc)
      o.repeats = std::max(1, next_int());
    else if (a == "--device" && i + 1 < argc)
      o.device = argv[++i];
    else if (a == "--work-group" && i + 1 < argc)
      o.shape.group_size = static_cast<size_t>(next_int());
    else if (a == "--items" && i + 1 < argc)
      o.shape.items_per_item = static_cast<size_t>(next_int());
    else if (a == "--local-reorder")
      o.shape.local_reorder = true;
    else {
      std::fprintf(stderr,
                   "usage: bench_sort [--min-log A] [--max-log B] [--step S] [--repeats R] "
                   "[--device SPEC] [--work-group W --items I [--local-reorder]]\n");
      return 2;
    }
  }
  if (o.min_log < 0 || o.max_log > 28 || o.min_log > o.max_log) {
    std::fprintf(stderr, "bench_sort: sizes 2^%d..2^%d out of range (0..28)\n", o.min_log,
                 o.max_log);
    return 2;
  }
  if ((o.shape.group_size == 0) != (o.shape.items_per_item == 0)) {
    std::fprintf(stderr, "bench_sort: give --work-group and --items together\n");
    return 2;
  }
  auto ctx = device::Context::create(o.device);
  if (!ctx) return fail(ctx.status());
  const auto shape =
      o.shape.group_size ? o.shape : pipeline::preferred_tile_shape(ctx.value()->info());
  std::printf("machine: %s\n", describe(machine_info()).c_str());
  std::printf("OpenCL device: %s\n", ctx.value()->info().describe().c_str());
  std::printf(
      "tile shape (work-group x items per work-item): %s; best of %d runs; OpenCL = kernel time, "
      "host = one thread\n\n",
      shape.describe().c_str(), o.repeats);
  if (Status st = bench_sort(*ctx.value(), o); !st.is_ok()) return fail(st);
  if (Status st = bench_compaction(*ctx.value(), o); !st.is_ok()) return fail(st);
  return 0;
}
