/* Shared device helpers of the data-parallel primitives (radix sort, stream
 * compaction; thesis §2.5, §5.1, §5.3).
 *
 * Every primitive works on tiles: one work-group of LUX_PRIM_WG work-items
 * owns LUX_PRIM_TILE = LUX_PRIM_WG * LUX_PRIM_ITEMS consecutive elements.
 * The host launches ceil(capacity / tile) work-groups; the live element count
 * is read from a device buffer (DESIGN.md: live counts stay on the device),
 * so work-groups whose tile starts at or past the count exit at once.
 *
 * Build options (set by server/engine/bake/primitives/tile_shape.cpp):
 *   LUX_PRIM_WG     work-group size, a power of two
 *   LUX_PRIM_ITEMS  elements per work-item in one tile */
#ifndef LUXEL_PRIMITIVES_TILE_H
#define LUXEL_PRIMITIVES_TILE_H

#ifndef LUX_PRIM_WG
#error "build with -DLUX_PRIM_WG=<work-group size, a power of two>"
#endif
#ifndef LUX_PRIM_ITEMS
#error "build with -DLUX_PRIM_ITEMS=<elements per work-item>"
#endif

#define LUX_PRIM_TILE (LUX_PRIM_WG * LUX_PRIM_ITEMS)

/* PoCL 3.1 miscompiles loops whose trip count differs between the work-items
 * of a group when the kernel has barriers (the body ran once past the
 * bound). Every loop in these kernels therefore has a trip count that is the
 * same for the whole group and guards each step with an `if`:
 *   for (uint k = 0; k < LUX_PRIM_ITEMS; ++k) {
 *     const uint i = k * LUX_PRIM_WG + lid;
 *     if (i < tile_n) ...
 *   } */

#define LUX_PRIM_KERNEL __kernel __attribute__((reqd_work_group_size(LUX_PRIM_WG, 1, 1)))

/* The live count, an int written by an earlier kernel. Clamped to
 * [0, capacity] so that a corrupt count can never index past the buffers. */
inline uint lux_live_count(__global const int* count, uint capacity) {
  const int n = *count;
  return n <= 0 ? 0u : min((uint)n, capacity);
}

inline uint lux_tiles_for(uint n) {
  return (n + LUX_PRIM_TILE - 1u) / LUX_PRIM_TILE;
}

/* Exclusive prefix sum of one value per work-item across the work-group
 * (Hillis-Steele in local memory: OpenCL 1.2 has no work_group_scan and no
 * portable SIMD-group shuffles, so the §5.3 SIMD scan becomes this).
 * scratch: LUX_PRIM_WG uints. Every work-item of the group must call it.
 * Returns the sum of the values of lower work-items; *total is the group sum. */
inline uint lux_group_scan_exclusive(uint value, __local uint* scratch, uint* total) {
  const uint lid = get_local_id(0);
  scratch[lid] = value;
  barrier(CLK_LOCAL_MEM_FENCE);
  for (uint offset = 1; offset < LUX_PRIM_WG; offset <<= 1) {
    const uint add = lid >= offset ? scratch[lid - offset] : 0u;
    barrier(CLK_LOCAL_MEM_FENCE);
    scratch[lid] += add;
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  const uint inclusive = scratch[lid];
  *total = scratch[LUX_PRIM_WG - 1];
  barrier(CLK_LOCAL_MEM_FENCE); /* the caller may reuse scratch at once */
  return inclusive - value;
}

/* In-place exclusive prefix sum of data[0..n) by a single work-group; returns
 * the total to every work-item. Each work-item runs serially over one
 * contiguous chunk, and the chunk sums are scanned across the group. Used for
 * the per-tile counts (§2.5 "scan" phase), whose length is capacity / tile. */
inline uint lux_scan_in_one_group(__global uint* data, uint n, __local uint* scratch) {
  const uint lid = get_local_id(0);
  const uint chunk = (n + LUX_PRIM_WG - 1u) / LUX_PRIM_WG;
  const uint begin = min(lid * chunk, n);
  const uint end = min(begin + chunk, n);
  uint sum = 0;
  for (uint k = 0; k < chunk; ++k)
    if (begin + k < end) sum += data[begin + k];
  uint total;
  uint running = lux_group_scan_exclusive(sum, scratch, &total);
  for (uint k = 0; k < chunk; ++k) {
    if (begin + k < end) {
      const uint v = data[begin + k];
      data[begin + k] = running;
      running += v;
    }
  }
  return total;
}

#endif /* LUXEL_PRIMITIVES_TILE_H */
