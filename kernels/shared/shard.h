/* Distributed bakes: which sample indices of every texel's progressive
 * sequence (kernels/sampling/sequence.h, thesis §6.2) a shard traces, so that
 * the shards of one bake trace disjoint parts whose union is exactly the
 * samples [0, S) one machine would trace. Compiled both as OpenCL C (raygen)
 * and as C++ (the engine's sample targets, tests).
 *
 * Block interleaving: a shard's local index i (its texel's own sample count,
 * as raygen counts it) maps to the global index
 *   ((i >> b) * N + k) << b | (i & (B - 1)),   B = 2^b = LUX_SHARD_BLOCK,
 * i.e. the sequence is cut into aligned blocks of B consecutive indices and
 * block j goes to shard j mod N. The sequence shuffles the index by an Owen
 * scramble of its bits read low to high, which keeps aligned blocks of 2^m
 * indices together, so every aligned block of B samples is a (0,b,2)-net of
 * the Sobol points: each shard traces whole nets, stratified in every
 * dimension pair. The plain interleaving i * N + k would fix the low log2 N
 * bits of every index a shard draws; those bits become the leading bits of
 * the first Sobol coordinate (van der Corput reverses the bits), so all of a
 * shard's points would fall in one 1/N-wide stratum of that dimension and
 * each shard's estimate alone would be strongly biased-by-stratum (unbiased
 * only over seeds), with the error of far fewer effective samples
 * (docs/accuracy.md "Distributed bakes" measures it). B = 16 keeps
 * 4x4-stratified nets per shard while leaving the shards' loads within one
 * block of each other. Global indices are 32-bit like the sequence's: a shard
 * without a samples rule wraps after about 2^32 / N samples per texel. */
#ifndef LUXEL_SHARED_SHARD_H
#define LUXEL_SHARED_SHARD_H

#include "shared/compat.h"

#define LUX_SHARD_BLOCK_BITS 4u
#define LUX_SHARD_BLOCK (1u << LUX_SHARD_BLOCK_BITS)

#ifndef __OPENCL_C_VERSION__
namespace luxel::cl {
#endif

/* Global sample index of shard `shard`'s local index i (count <= 1: i). */
LUX_INLINE uint lux_shard_sample_index(uint i, uint shard, uint count) {
  if (count <= 1u) return i;
  return (((i >> LUX_SHARD_BLOCK_BITS) * count + shard) << LUX_SHARD_BLOCK_BITS) |
         (i & (LUX_SHARD_BLOCK - 1u));
}

/* How many of the global indices [0, total) shard `shard` of `count` traces:
 * its full blocks, plus the incomplete last block when that block is its. */
LUX_INLINE uint lux_shard_samples(uint total, uint shard, uint count) {
  if (count <= 1u) return total;
  const uint blocks = total >> LUX_SHARD_BLOCK_BITS; /* full blocks */
  const uint rest = total & (LUX_SHARD_BLOCK - 1u);
  const uint mine = blocks / count + (shard < blocks % count ? 1u : 0u);
  return (mine << LUX_SHARD_BLOCK_BITS) + (blocks % count == shard ? rest : 0u);
}

#ifndef __OPENCL_C_VERSION__
}  // namespace luxel::cl
#endif

#endif /* LUXEL_SHARED_SHARD_H */
