// The coordinator's merge cost per shard, in C++ (the figure the scaling
// model, tests/bench/shard_model.py --merge-rate, takes): W shard states of T
// covered texels in the accumulators.bin layout (shards/checkpoint.h) are
// written, then read back and folded one at a time as the coordinator does
// (read_checkpoint, pipeline::ShardMerger: Chan et al.'s parallel Welford
// per texel), each step timed; peak RSS at the end (the fold holds one
// shard's state and the double accumulators, whatever W).
//
//   bench_shard_merge [--texels T] [--shards W] [--sh2] [--dir D]
//
// The states are synthetic (random means, M2 and weights that pass the
// merge's checks): the merge's cost does not depend on the values.
#include "shards/shard_merge.h"

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "common/clock.h"
#include "common/status.h"
#include "kernels/shared/bake.h"
#include "shards/checkpoint.h"

namespace {

using Clock = std::chrono::steady_clock;
using luxel::seconds_since;
using luxel::pipeline::BakeCheckpoint;

BakeCheckpoint synthetic_shard(size_t texels, uint32_t index, uint32_t count, bool sh2) {
  std::mt19937 rng(1234 + index);
  std::uniform_real_distribution<float> u(0.1f, 2.0f);
  BakeCheckpoint c;
  c.fingerprint = "bench-shard-merge";
  c.shard_index = index;
  c.shard_count = count;
  c.width = 4096;
  c.height = static_cast<uint32_t>((texels + 4095) / 4096);
  c.mean.resize(texels);
  c.m2.resize(texels);
  c.weight.resize(texels);
  c.spp.resize(texels);
  for (size_t t = 0; t < texels; ++t) {
    c.mean[t] = {u(rng), u(rng), u(rng), 1.0f};
    c.m2[t] = {u(rng), u(rng), u(rng), 0.0f};
    c.spp[t] = 16;
    c.weight[t] = {16.0f, 16.0f};
  }
  c.paths_done = uint64_t{16} * texels;
  if (sh2) {
    constexpr uint32_t kLobes = 9;
    c.basis_layout = {kLobes | (LUX_SOLVER_PROJECTION << 16)};
    c.basis.resize(texels * (1 + kLobes));
    for (size_t t = 0; t < texels; ++t) {
      c.basis[t * (1 + kLobes)] = {16.0f, 0.0f, 0.0f, 0.0f};
      for (uint32_t l = 1; l <= kLobes; ++l)
        c.basis[t * (1 + kLobes) + l] = {u(rng), u(rng), u(rng), 0.0f};
    }
  }
  return c;
}

}  // namespace

int main(int argc, char** argv) {
  size_t texels = 1u << 20;
  uint32_t shards = 4;
  bool sh2 = false;
  std::string dir = std::filesystem::temp_directory_path().string() + "/luxel_bench_shard_merge";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> const char* {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--texels") {
      texels = std::strtoull(next(), nullptr, 10);
    } else if (a == "--shards") {
      shards = static_cast<uint32_t>(std::strtoul(next(), nullptr, 10));
    } else if (a == "--sh2") {
      sh2 = true;
    } else if (a == "--dir") {
      dir = next();
    } else {
      std::fprintf(stderr,
                   "usage: bench_shard_merge [--texels T] [--shards W] [--sh2] [--dir D]\n");
      return 2;
    }
  }
  if (texels == 0 || shards < 2) {
    std::fprintf(stderr, "--texels must be > 0 and --shards >= 2\n");
    return 2;
  }
  std::filesystem::create_directories(dir);
  std::vector<std::string> paths;
  uintmax_t bytes = 0;
  for (uint32_t k = 0; k < shards; ++k) {
    paths.push_back(dir + luxel::strprintf("/%u.bin", k));
    if (auto st = luxel::pipeline::write_checkpoint(paths.back(),
                                                    synthetic_shard(texels, k, shards, sh2));
        !st.is_ok()) {
      std::fprintf(stderr, "write: %s\n", st.to_string().c_str());
      return 1;
    }
    bytes += std::filesystem::file_size(paths.back());
  }
  // As the coordinator merges (coordinator.cpp, fold_downloaded): each
  // shard read back and folded in index order, one state in memory at a time.
  double read_s = 0, merge_s = 0;
  luxel::pipeline::ShardMerger merger;
  for (const std::string& p : paths) {
    const auto t_read = Clock::now();
    auto c = luxel::pipeline::read_checkpoint(p);
    read_s += seconds_since(t_read);
    if (!c) {
      std::fprintf(stderr, "read: %s\n", c.status().to_string().c_str());
      return 1;
    }
    const auto t_merge = Clock::now();
    if (auto st = merger.add(c.value()); !st.is_ok()) {
      std::fprintf(stderr, "merge: %s\n", st.to_string().c_str());
      return 1;
    }
    merge_s += seconds_since(t_merge);
  }
  const auto t_finish = Clock::now();
  auto merged = merger.finish();
  merge_s += seconds_since(t_finish);
  if (!merged) {
    std::fprintf(stderr, "merge: %s\n", merged.status().to_string().c_str());
    return 1;
  }
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  const double merged_texels = double(texels) * shards;
  std::printf(
      "shards %u x %zu texels%s: %.1f MB of accumulators.bin (%.1f B/texel)\n"
      "read (checksum + parse): %.3f s, %.0f MB/s\n"
      "merge: %.3f s, %.1f M texels/s (shard texels merged per second)\n"
      "peak RSS %.0f MiB\n",
      shards, texels, sh2 ? " with SH2" : "", bytes / 1e6, double(bytes) / merged_texels, read_s,
      bytes / 1e6 / read_s, merge_s, merged_texels / merge_s / 1e6, ru.ru_maxrss / 1024.0);
  for (const std::string& p : paths) std::filesystem::remove(p);
  // Sanity: every texel got every shard's 16 samples.
  for (uint32_t n : merged.value().spp)
    if (n != 16 * shards) {
      std::fprintf(stderr, "merged sample counts wrong: %u\n", n);
      return 1;
    }
  return 0;
}
