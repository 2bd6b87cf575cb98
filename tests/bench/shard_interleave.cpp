// bench_shard_interleave: the error of one shard of a distributed bake
// against a converged reference, for the block interleaving of
// kernels/shared/shard.h, and (run with LUXEL_KERNEL_DIR pointing at a copy
// of kernels/ with LUX_SHARD_BLOCK_BITS 0u) the plain interleaving i*N+k.
// A whole bake of the shard's sample count is the baseline: a shard that
// traces well-stratified nets should match it.
//
//   bench_shard_interleave [--resolution R] [--reference-spp N] [--spp S]
//                          [--shards N] [--seeds K] SCENE
//
// Prints the RMSE over covered texels and RGB, averaged over seeds and
// shards (docs/accuracy.md "Distributed bakes"). S must be a multiple of
// 16 N so both interleavings give every shard S / N samples.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bake/bake.h"
#include "device/context.h"
#include "scene/gltf_import.h"

using namespace luxel;

namespace {

double rmse(const std::vector<float>& x, const std::vector<float>& ref) {
  double sum = 0;
  size_t n = 0;
  for (size_t i = 0; i + 3 < ref.size(); i += 4) {
    if (!(ref[i + 3] > 0)) continue;  // uncovered
    for (int c = 0; c < 3; ++c) {
      const double d = double{x[i + c]} - ref[i + c];
      sum += d * d;
      ++n;
    }
  }
  return n ? std::sqrt(sum / static_cast<double>(n)) : 0;
}

}  // namespace

int main(int argc, char** argv) {
  int resolution = 32;
  uint32_t reference_spp = 4096, spp = 256, shards = 4, seeds = 4;
  std::string scene_path;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&] { return i + 1 < argc ? std::strtoul(argv[++i], nullptr, 10) : 0ul; };
    if (a == "--resolution")
      resolution = static_cast<int>(next());
    else if (a == "--reference-spp")
      reference_spp = static_cast<uint32_t>(next());
    else if (a == "--spp")
      spp = static_cast<uint32_t>(next());
    else if (a == "--shards")
      shards = static_cast<uint32_t>(next());
    else if (a == "--seeds")
      seeds = static_cast<uint32_t>(next());
    else
      scene_path = a;
  }
  if (scene_path.empty() || shards < 2 || spp % (16 * shards) != 0) {
    std::fprintf(stderr,
                 "usage: bench_shard_interleave [options] SCENE (spp a multiple of 16 N)\n");
    return 2;
  }
  auto scene = scene::import_gltf_file(scene_path);
  auto ctx = device::Context::create();
  if (!scene || !ctx) {
    std::fprintf(stderr, "%s\n", (!scene ? scene.status() : ctx.status()).to_string().c_str());
    return 1;
  }
  pipeline::BakeSettings base;
  base.atlas.resolution = resolution;
  base.max_bounces = 2;
  base.adaptive = false;
  base.progress_interval_s = 1e9;
  auto run = [&](pipeline::BakeSettings s) -> std::vector<float> {
    auto r = pipeline::bake(scene.value(), s, *ctx.value());
    if (!r) {
      std::fprintf(stderr, "%s\n", r.status().to_string().c_str());
      std::exit(1);
    }
    return r.value().irradiance;
  };
  pipeline::BakeSettings ref_settings = base;
  ref_settings.samples_per_texel = reference_spp;
  ref_settings.seed = 999983;
  const std::vector<float> ref = run(ref_settings);

  double shard_sum = 0, whole_sum = 0;
  for (uint32_t seed = 1; seed <= seeds; ++seed) {
    for (uint32_t k = 0; k < shards; ++k) {
      pipeline::BakeSettings s = base;
      s.seed = seed;
      s.samples_per_texel = spp;
      s.shard_index = k;
      s.shard_count = shards;
      shard_sum += rmse(run(s), ref);
    }
    pipeline::BakeSettings w = base;
    w.seed = seed;
    w.samples_per_texel = spp / shards;
    whole_sum += rmse(run(w), ref);
  }
  std::printf(
      "reference %u spp; shard of %u spp / %u shards (%u samples each), mean over %u seeds x "
      "%u shards: RMSE %.5g; whole bake of %u spp: RMSE %.5g\n",
      reference_spp, spp, shards, spp / shards, seeds, shards, shard_sum / (seeds * shards),
      spp / shards, whole_sum / seeds);
  return 0;
}
