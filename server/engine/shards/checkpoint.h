// Bake checkpoints: the accumulation state of a bake, enough to continue it
// after a restart and produce the same bits as an uninterrupted bake (the
// texel domain and every sample index derive from the path count, which is
// part of the state). Written atomically with a checksum; a torn or
// mismatched file is refused, never half-read.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/status.h"
#include "kernels/shared/compat.h"

namespace luxel::pipeline {

// float4 of one texel's first-bounce histograms (LUX_GUIDE_STRIDE).
inline constexpr size_t kGuideStride = 8;

struct BakeCheckpoint {
  // What the state belongs to: a hash of the scene content and of the
  // settings that shape the result. Resuming with another fingerprint fails.
  // Shards of one bake (shards/shard_merge.h) share it: it leaves out
  // the shard fields below.
  std::string fingerprint;
  // Distributed bakes (version 4): the shard this state belongs to
  // (shard_count 1: the whole bake, or a merge of all its shards).
  uint32_t shard_index = 0, shard_count = 1;
  uint32_t width = 0, height = 0;
  uint64_t paths_done = 0;
  uint32_t iteration = 0;
  double elapsed_s = 0;  // tracing time before the checkpoint
  uint64_t nonfinite = 0;
  std::vector<double> series;  // ErrorSample fields flattened, series_stride per point
  size_t series_stride = 7;    // 7 (with rmse, rel_mse); 5 in version-1 files
  // Per covered texel, in the order of SampleInfo::covered_texels (version
  // 3). Versions 1-2 stored whole images (per_texel): the bake keeps the
  // covered texels on restore (compact_checkpoint).
  bool per_texel = false;
  std::vector<cl::float4> mean, m2;
  std::vector<cl::float2> weight;
  std::vector<uint32_t> spp;
  // Directional encodings: entries * stride float4 (empty without encodings).
  std::vector<cl::float4> basis;
  // How `basis` is laid out (version 4; empty in older files): per encoding
  // in state order, its lobe count | solver << 16 (LUX_SOLVER_*). Its state
  // is one header float4 (x = sum of weights) then the lobes.
  std::vector<uint32_t> basis_layout;
  // The radiance cache's means per covered slot (version 5; empty without
  // the cache, kernels/bake/radiance_cache.h): a resumed bake reads the
  // cache the interrupted one had, so it gives the same bits.
  std::vector<cl::float4> radiance_cache;
  // First-bounce guiding's histograms, kGuideStride float4 per covered slot
  // (version 5; empty without guiding, kernels/bake/guiding.h).
  std::vector<cl::float4> guide;
  // Bakes in tiles (bake/tile_plan.h): the state above covers every
  // covered texel (finished tiles, the current one, zeros after it) and
  // paths_done / nonfinite are the current tile's. Empty for a bake in one
  // tile. Fields: kTileFields below.
  std::vector<double> tile;
};

// BakeCheckpoint::tile: the current tile's index, first and end slot, the
// tile count, then the finished tiles' paths, non-finite drops, relative
// error sum, RMSE^2 and relMSE sums and minimum spp.
enum TileField {
  kTileIndex,
  kTileBegin,
  kTileEnd,
  kTileCount,
  kTileDonePaths,
  kTileDoneNonfinite,
  kTileDoneError,
  kTileDoneSq,
  kTileDoneRel,
  kTileDoneMinSpp,
  kTileFields
};

// Binary, little-endian, "LUXCKPT5" magic (versions 1, without the basis
// state, 2, whole images, 3, without the shard fields and basis layout, and
// 4, without the radiance cache, are still read), 128-bit checksum at the
// end.
Status write_checkpoint(const std::string& path, const BakeCheckpoint& checkpoint);
// NOT_FOUND when absent, DATA_LOSS when torn or corrupt.
Result<BakeCheckpoint> read_checkpoint(const std::string& path);

// A whole-image (per_texel) checkpoint's state at the given texels (the
// per-slot form); other fields are copied.
BakeCheckpoint compact_checkpoint(const BakeCheckpoint& c, const std::vector<uint32_t>& texels);

// The per-slot state of slots [begin, end) (mean, M2, weight, spp, basis);
// other fields are copied, except the series and tile record.
BakeCheckpoint slice_checkpoint(const BakeCheckpoint& c, size_t begin, size_t end);

}  // namespace luxel::pipeline
