/* Stable LSD radix sort of uint keys (optionally carrying 32-bit values), one
 * 4-bit digit per pass (thesis §2.5 after Harada and Howes [56]; only as many
 * passes as the key range needs, §5.3). Per pass the host enqueues:
 *
 *   radix_histogram  per tile: how many keys have each digit value, stored
 *                    digit-major: histogram[digit * tiles + tile]
 *   radix_scan       exclusive prefix sum over that table: entry (d, t) becomes
 *                    where tile t's keys with digit d start in the output (all
 *                    keys with a lower digit, plus digit d in lower tiles)
 *   radix_scatter    per tile: the stable rank of each key inside the tile
 *                    (a local scan of per-work-item digit counts), then keys
 *                    and values written to their output slots
 *
 * and radix_copy once at the end when an odd number of passes left the result
 * in the scratch buffers. `tiles` is derived from the live count in every
 * kernel, so the scan only covers tiles that hold live keys.
 *
 * LUX_PRIM_LOCAL_REORDER (GPUs): the scatter reorders each tile in local
 * memory before writing it out, for coalesced stores. Without it (CPUs) each
 * work-item writes its run straight to the output. */

#include "primitives/tile.h"

#define LUX_RADIX_DIGITS 16u
/* One spare slot per 32 entries of the per-work-item digit table, so that the
 * work-items of the table scan (each walking 16 consecutive entries) do not
 * all hit the same local memory bank. */
#define LUX_PAD(i) ((i) + ((i) >> 5))
#define LUX_DIGIT_TABLE LUX_PAD(LUX_RADIX_DIGITS* LUX_PRIM_WG)

inline uint lux_digit(uint key, uint shift, uint mask) {
  return (key >> shift) & mask;
}

LUX_PRIM_KERNEL void radix_histogram(__global const uint* keys, __global const int* count,
                                     const uint capacity, const uint shift, const uint mask,
                                     __global uint* histogram) {
  __local uint table[LUX_DIGIT_TABLE]; /* (digit, work-item) counts */
  const uint n = lux_live_count(count, capacity);
  const uint tile = get_group_id(0);
  const uint base = tile * LUX_PRIM_TILE;
  if (base >= n) return; /* uniform across the work-group */
  const uint tiles = lux_tiles_for(n);
  const uint tile_n = min((uint)LUX_PRIM_TILE, n - base);
  const uint lid = get_local_id(0);

  uint count_of[LUX_RADIX_DIGITS];
  for (uint d = 0; d < LUX_RADIX_DIGITS; ++d) count_of[d] = 0;
  /* Strided, so neighbouring work-items read neighbouring keys. */
  for (uint k = 0; k < LUX_PRIM_ITEMS; ++k) {
    const uint i = k * LUX_PRIM_WG + lid;
    if (i < tile_n) count_of[lux_digit(keys[base + i], shift, mask)] += 1;
  }
  for (uint d = 0; d < LUX_RADIX_DIGITS; ++d) table[LUX_PAD(d * LUX_PRIM_WG + lid)] = count_of[d];
  barrier(CLK_LOCAL_MEM_FENCE);

  /* Tree reduction over the work-items, all 16 digits at once. */
  for (uint stride = LUX_PRIM_WG / 2; stride > 0; stride >>= 1) {
    if (lid < stride) {
      for (uint d = 0; d < LUX_RADIX_DIGITS; ++d)
        table[LUX_PAD(d * LUX_PRIM_WG + lid)] += table[LUX_PAD(d * LUX_PRIM_WG + lid + stride)];
    }
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  /* A loop, not `if (lid < 16)`: the work-group may be smaller than 16. */
  for (uint d0 = 0; d0 < LUX_RADIX_DIGITS; d0 += LUX_PRIM_WG) {
    const uint d = d0 + lid;
    if (d < LUX_RADIX_DIGITS) histogram[d * tiles + tile] = table[LUX_PAD(d * LUX_PRIM_WG)];
  }
}

/* One work-group. */
LUX_PRIM_KERNEL void radix_scan(__global uint* histogram, __global const int* count,
                                const uint capacity) {
  __local uint scratch[LUX_PRIM_WG];
  const uint n = lux_live_count(count, capacity);
  (void)lux_scan_in_one_group(histogram, LUX_RADIX_DIGITS * lux_tiles_for(n), scratch);
}

LUX_PRIM_KERNEL void radix_scatter(__global const uint* keys_in, __global const uint* values_in,
                                   __global uint* keys_out, __global uint* values_out,
                                   const int with_values, __global const int* count,
                                   const uint capacity, const uint shift, const uint mask,
                                   __global const uint* histogram) {
  __local uint table[LUX_DIGIT_TABLE];
  __local uint scratch[LUX_PRIM_WG];
#if LUX_PRIM_LOCAL_REORDER
  __local uint tile_keys[LUX_PRIM_TILE];
  __local uint tile_values[LUX_PRIM_TILE];
  __local uint out_base[LUX_RADIX_DIGITS];
#endif

  const uint n = lux_live_count(count, capacity);
  const uint tile = get_group_id(0);
  const uint base = tile * LUX_PRIM_TILE;
  if (base >= n) return; /* uniform across the work-group */
  const uint tiles = lux_tiles_for(n);
  const uint tile_n = min((uint)LUX_PRIM_TILE, n - base);
  const uint lid = get_local_id(0);
  /* Work-item lid owns the contiguous run [run_begin, run_end) of the tile.
   * Ranking keys in run order, and runs in work-item order, is what makes
   * the sort stable. */
  const uint run_begin = min(lid * LUX_PRIM_ITEMS, tile_n);
  const uint run_end = min(run_begin + LUX_PRIM_ITEMS, tile_n);

#if LUX_PRIM_LOCAL_REORDER
  for (uint k = 0; k < LUX_PRIM_ITEMS; ++k) {
    const uint i = k * LUX_PRIM_WG + lid;
    if (i < tile_n) {
      tile_keys[i] = keys_in[base + i];
      if (with_values) tile_values[i] = values_in[base + i];
    }
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  /* The tile is rewritten in digit order below, so the run is kept in
   * registers (LUX_PRIM_ITEMS is small on GPUs). */
  uint keys[LUX_PRIM_ITEMS];
  uint values[LUX_PRIM_ITEMS];
  for (uint k = 0; k < LUX_PRIM_ITEMS; ++k) {
    const uint i = run_begin + k;
    keys[k] = i < run_end ? tile_keys[i] : 0u;
    values[k] = i < run_end && with_values ? tile_values[i] : 0u;
  }
#define LUX_RUN_KEY(k) keys[k]
#else
#define LUX_RUN_KEY(k) keys_in[base + run_begin + (k)]
#endif

  uint slot_of[LUX_RADIX_DIGITS];
  for (uint d = 0; d < LUX_RADIX_DIGITS; ++d) slot_of[d] = 0;
  for (uint k = 0; k < LUX_PRIM_ITEMS; ++k)
    if (run_begin + k < run_end) slot_of[lux_digit(LUX_RUN_KEY(k), shift, mask)] += 1;
  for (uint d = 0; d < LUX_RADIX_DIGITS; ++d) table[LUX_PAD(d * LUX_PRIM_WG + lid)] = slot_of[d];
  barrier(CLK_LOCAL_MEM_FENCE);

  /* Exclusive scan of the digit-major table: entry (d, t) becomes the
   * tile-local position of work-item t's first key with digit d. */
  {
    const uint first = lid * LUX_RADIX_DIGITS;
    uint sum = 0;
    for (uint j = 0; j < LUX_RADIX_DIGITS; ++j) sum += table[LUX_PAD(first + j)];
    uint total;
    uint running = lux_group_scan_exclusive(sum, scratch, &total);
    for (uint j = 0; j < LUX_RADIX_DIGITS; ++j) {
      const uint v = table[LUX_PAD(first + j)];
      table[LUX_PAD(first + j)] = running;
      running += v;
    }
  }
  barrier(CLK_LOCAL_MEM_FENCE);

  /* Output slot of tile-local position p with digit d: the digit's global
   * start for this tile (scanned histogram) minus its tile-local start, plus
   * p (modular uint arithmetic, the sum is exact). */
#if LUX_PRIM_LOCAL_REORDER
  /* GPUs: reorder the tile in local memory first, so that neighbouring
   * work-items write neighbouring slots of one digit's run (coalesced). */
  for (uint d0 = 0; d0 < LUX_RADIX_DIGITS; d0 += LUX_PRIM_WG) {
    const uint d = d0 + lid;
    if (d < LUX_RADIX_DIGITS)
      out_base[d] = histogram[d * tiles + tile] - table[LUX_PAD(d * LUX_PRIM_WG)];
  }
  for (uint d = 0; d < LUX_RADIX_DIGITS; ++d) slot_of[d] = table[LUX_PAD(d * LUX_PRIM_WG + lid)];
  for (uint k = 0; k < LUX_PRIM_ITEMS; ++k) {
    if (run_begin + k < run_end) {
      const uint slot = slot_of[lux_digit(keys[k], shift, mask)]++;
      tile_keys[slot] = keys[k];
      if (with_values) tile_values[slot] = values[k];
    }
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  for (uint k = 0; k < LUX_PRIM_ITEMS; ++k) {
    const uint i = k * LUX_PRIM_WG + lid;
    if (i < tile_n) {
      const uint key = tile_keys[i];
      const uint dst = out_base[lux_digit(key, shift, mask)] + i;
      keys_out[dst] = key;
      if (with_values) values_out[dst] = tile_values[i];
    }
  }
#else
  /* CPUs: write straight from the run; each work-item's 16 output streams
   * are sequential, which is what a cache wants. */
  for (uint d = 0; d < LUX_RADIX_DIGITS; ++d)
    slot_of[d] = histogram[d * tiles + tile] - table[LUX_PAD(d * LUX_PRIM_WG)] +
                 table[LUX_PAD(d * LUX_PRIM_WG + lid)];
  for (uint k = 0; k < LUX_PRIM_ITEMS; ++k) {
    if (run_begin + k < run_end) {
      const uint src = base + run_begin + k;
      const uint key = keys_in[src];
      const uint dst = slot_of[lux_digit(key, shift, mask)]++;
      keys_out[dst] = key;
      if (with_values) values_out[dst] = values_in[src];
    }
  }
#endif
#undef LUX_RUN_KEY
}

/* Copies the live prefix back after an odd number of passes; tiled like the
 * other kernels (one work-item per key would mean one work-group per key
 * with the CPU shape). */
LUX_PRIM_KERNEL void radix_copy(__global const uint* keys_in, __global const uint* values_in,
                                __global uint* keys_out, __global uint* values_out,
                                const int with_values, __global const int* count,
                                const uint capacity) {
  const uint n = lux_live_count(count, capacity);
  const uint base = get_group_id(0) * LUX_PRIM_TILE;
  for (uint k = 0; k < LUX_PRIM_ITEMS; ++k) {
    const uint i = base + k * LUX_PRIM_WG + get_local_id(0);
    if (i < n) {
      keys_out[i] = keys_in[i];
      if (with_values) values_out[i] = values_in[i];
    }
  }
}
