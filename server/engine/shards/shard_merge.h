// Distributed bakes: one bake split across workers by sample index
// (kernels/shared/shard.h), and the exact merge of their accumulators.
//
// Each shard is an ordinary bake with settings.shard_index / shard_count
// set; when it finishes, BakeResult::final_state holds its per-texel
// accumulators in the checkpoint format (shards/checkpoint.h; the service
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

#include "bake/bake.h"
#include "common/status.h"
#include "shards/checkpoint.h"

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

// The same merge as a fold, for a coordinator that reads one shard at a
// time: add() the states in shard-index order (0, 1, ...), then finish().
// It holds one set of double accumulators (88 B per covered texel, plus
// 32 B per encoding value) instead of every shard's state, and gives the
// same bits as merge_shard_states. add() refuses, naming the shard, what
// merge_shard_states refuses, and a shard out of order; finish() a missing
// one. The merger can be reused after finish().
class ShardMerger {
 public:
  // threads: how many fold texel ranges side by side (0: one per hardware
  // thread, ranges of at least 2^16 texels); the bits do not depend on it.
  explicit ShardMerger(unsigned threads = 0) : threads_(threads) {}
  Status add(const BakeCheckpoint& shard);
  Result<BakeCheckpoint> finish();
  uint32_t added() const { return added_; }

 private:
  friend Result<BakeCheckpoint> merge_shard_states(std::vector<BakeCheckpoint> shards);
  // check = false: the caller ran check_shard on this state already.
  Status add(const BakeCheckpoint& shard, bool check);
  void reset();
  unsigned threads_ = 0;
  BakeCheckpoint out_;  // header fields, then the result
  uint32_t added_ = 0;
  size_t texels_ = 0, stride_ = 0;
  std::vector<double> acc_;     // per texel: mean[4], m2[4], sum w, sum w^2
  std::vector<uint64_t> spp_;   // per texel
  std::vector<double> basis_;   // per encoding value: 4 running means
  std::vector<double> totals_;  // per texel and encoding: the weight total
};

// Outputs of a merged state: bake() resumed from `merged` with settings.shard_count = 1,
// tracing nothing more; the result's termination is `why`, the rule that
// ended the shards.
//
// `settings` are the whole bake's (shard fields ignored, adaptive off); the
// hooks' fingerprint, resume and finish_now are set here. With why =
// kSamples every texel of `merged` must hold settings.samples_per_texel
// (a shard missing or stopped early otherwise); with a stop by time, error
// or request the shards stopped where they were, so texels may hold fewer
// (never more) and differ: the merged state is still exactly the union of
// the sample indices the shards traced (possibly none: a bake finished
// before it started). INVALID_ARGUMENT otherwise.
Result<BakeResult> finish_merged_bake(const scene::Scene& scene, const BakeSettings& settings,
                                      device::Context& ctx, const BakeCheckpoint& merged,
                                      Termination why = Termination::kSamples,
                                      const BakeHooks& hooks = {});

}  // namespace luxel::pipeline
