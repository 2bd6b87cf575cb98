// Distributed bakes: one bake split across workers by sample index
// (kernels/shared/shard.h), and the exact merge of their accumulators.
//
// Each shard is an ordinary bake with settings.shard_index / shard_count
// set; when it finishes, BakeResult::final_state holds its per-texel
// accumulators in the checkpoint format (pipeline/checkpoint.h; the service
// offers them as the artifact accumulators.bin). A coordinator collects the
// states of every shard, merges them here, and finishes the bake from the
// merged state: dilation, encodings, error estimates, outputs and manifest,
// without tracing another path.
//
// What merges exactly (up to float rounding): the Welford mean, M2 and
// weights (sum w, sum w^2) of every texel, its sample count, and the
// projection state of directional encodings (running means of the Monte
// Carlo moments). What does not, and is refused at submit (validate_settings):
// adaptive sampling (allocation by one machine's error estimates), the
// progressive least-squares solvers (order-dependent Gauss-Seidel state,
// Listing 7.1) and the Gaussian filter (which neighbour paths a texel
// gathers depends on the batching).
#pragma once

#include <vector>

#include "common/status.h"
#include "pipeline/bake.h"
#include "pipeline/checkpoint.h"

namespace luxel::pipeline {

// Shards of one bake (same fingerprint, same shard_count, each index once), merged in
// shard-index order: the parallel Welford formulas of Chan et al. for the weighted
// (sum w, sum w^2, mean, M2) per texel, spp summed, projection basis state as weighted means.
//
// The result has shard_index 0, shard_count 1, paths_done = the sum of the
// shards' samples, nonfinite summed, elapsed_s the longest shard's (they
// ran side by side), iteration the most of any shard, and no series or
// tile record (the shards' progress series do not add up to one bake's).
// INVALID_ARGUMENT naming the shard (by its position in `shards` and its
// shard_index) for mismatched or garbage input: another fingerprint, size or
// shard_count, a duplicate or missing index, an unfinished tiled state,
// non-finite or negative accumulators, sample counts that do not add up,
// progressive encoding state. Never crashes on bad input.
Result<BakeCheckpoint> merge_shard_states(std::vector<BakeCheckpoint> shards);

// Outputs of a merged state: bake() resumed from `merged` with settings.shard_count = 1,
// tracing nothing more (the merged sample count already meets settings.samples_per_texel).
//
// `settings` are the whole bake's (shard fields ignored, adaptive off); the
// hooks' fingerprint and resume are set from `merged`. INVALID_ARGUMENT when
// settings.samples_per_texel is 0 or is not what every texel of `merged`
// holds (the bake would trace more or be incomplete).
Result<BakeResult> finish_merged_bake(const scene::Scene& scene, const BakeSettings& settings,
                                      device::Context& ctx, const BakeCheckpoint& merged,
                                      const BakeHooks& hooks = {});

}  // namespace luxel::pipeline
