/* Stream compaction (thesis §5.1, after Wald [53]): keeps the live elements
 * whose flag is non-zero, in their original order, and writes how many were
 * kept to a device int. Three launches, like the §5.1 steps i-iii:
 *
 *   compact_count    per tile: number of set flags -> tile_counts[tile]; the
 *                    first work-item also snapshots the live input count, so
 *                    the later launches still see it when the caller's output
 *                    count aliases the input count
 *   compact_scan     one work-group: exclusive scan of tile_counts (the tiles'
 *                    output offsets) and the total -> *out_count
 *   compact_scatter  per tile: rank of each kept element inside the tile (a
 *                    local scan), then out[tile offset + rank] = value
 *
 * With with_values == 0 the kept element's index is written instead of a
 * value (the "index buffer of active paths" of §2.4.2 / §5.1). */

#include "primitives/tile.h"

#define LUX_DROPPED 0xFFFFFFFFu

LUX_PRIM_KERNEL void compact_count(__global const int* flags, __global const int* in_count,
                                   const uint capacity, __global uint* tile_counts,
                                   __global uint* live_snapshot) {
  __local uint scratch[LUX_PRIM_WG];
  const uint n = lux_live_count(in_count, capacity);
  const uint tile = get_group_id(0);
  const uint lid = get_local_id(0);
  if (tile == 0 && lid == 0) *live_snapshot = n;
  const uint base = tile * LUX_PRIM_TILE;
  if (base >= n) return; /* uniform across the work-group */
  const uint tile_n = min((uint)LUX_PRIM_TILE, n - base);
  uint kept = 0;
  for (uint k = 0; k < LUX_PRIM_ITEMS; ++k) {
    const uint i = k * LUX_PRIM_WG + lid;
    if (i < tile_n && flags[base + i] != 0) kept += 1;
  }
  uint total;
  (void)lux_group_scan_exclusive(kept, scratch, &total);
  if (lid == 0) tile_counts[tile] = total;
}

/* One work-group. */
LUX_PRIM_KERNEL void compact_scan(__global uint* tile_counts, __global const uint* live_snapshot,
                                  __global int* out_count) {
  __local uint scratch[LUX_PRIM_WG];
  const uint total = lux_scan_in_one_group(tile_counts, lux_tiles_for(*live_snapshot), scratch);
  if (get_local_id(0) == 0) *out_count = (int)total;
}

LUX_PRIM_KERNEL void compact_scatter(__global const uint* in_values, const int with_values,
                                     __global const int* flags, __global const uint* live_snapshot,
                                     __global const uint* tile_offsets, __global uint* out_values) {
  __local uint rank[LUX_PRIM_TILE]; /* output rank inside the tile, or LUX_DROPPED */
  __local uint scratch[LUX_PRIM_WG];
  const uint n = *live_snapshot;
  const uint tile = get_group_id(0);
  const uint base = tile * LUX_PRIM_TILE;
  if (base >= n) return; /* uniform across the work-group */
  const uint tile_n = min((uint)LUX_PRIM_TILE, n - base);
  const uint lid = get_local_id(0);

  for (uint k = 0; k < LUX_PRIM_ITEMS; ++k) {
    const uint i = k * LUX_PRIM_WG + lid;
    if (i < tile_n) rank[i] = flags[base + i] != 0 ? 1u : 0u;
  }
  barrier(CLK_LOCAL_MEM_FENCE);

  /* Work-item lid ranks the contiguous run [run_begin, run_end): runs in
   * work-item order keep the output in input order. */
  const uint run_begin = min(lid * LUX_PRIM_ITEMS, tile_n);
  const uint run_end = min(run_begin + LUX_PRIM_ITEMS, tile_n);
  uint kept = 0;
  for (uint k = 0; k < LUX_PRIM_ITEMS; ++k)
    if (run_begin + k < run_end) kept += rank[run_begin + k];
  uint total;
  uint next = lux_group_scan_exclusive(kept, scratch, &total);
  for (uint k = 0; k < LUX_PRIM_ITEMS; ++k) {
    const uint i = run_begin + k;
    if (i < run_end) rank[i] = rank[i] != 0 ? next++ : LUX_DROPPED;
  }
  barrier(CLK_LOCAL_MEM_FENCE);

  const uint tile_offset = tile_offsets[tile];
  for (uint k = 0; k < LUX_PRIM_ITEMS; ++k) {
    const uint i = k * LUX_PRIM_WG + lid;
    if (i < tile_n && rank[i] != LUX_DROPPED)
      out_values[tile_offset + rank[i]] = with_values ? in_values[base + i] : base + i;
  }
}
