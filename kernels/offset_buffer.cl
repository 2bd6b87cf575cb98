/* Offset buffer generation, thesis §3.2.1 / Listing 3.1.
 *
 * Input: texel indices of the paths, sorted (radix sort, §2.5); entries
 * >= texel_count are invalid (0xFFFFFFFF) and sorted to the end. The offset
 * buffer (texel_count + 1 uints) was filled with the sentinel beforehand (the
 * host enqueues fill_int from fill.cl). One work-item per path: work-item j
 * compares paths j and j + 1 and, where the texel changes, writes the
 * boundary j + 1 both after the previous texel and at the next one, so that
 * texels in a gap read as empty without any work-item scanning the gap.
 *
 * Differences from Listing 3.1, both so the reader needs no special case:
 * the boundary after the last valid texel is always written, and
 * offsets[texel_count] holds the number of paths with a valid texel (Listing
 * 3.2 reads texel_count there instead, which is only right when every path is
 * valid). The same number goes to *active_count_out. */

#include "primitives/offset_buffer.h"

__kernel void offset_generate(__global const uint* sorted_texels, __global const int* path_count,
                              const uint path_capacity, const uint texel_count,
                              __global uint* offsets, __global int* active_count_out) {
  const uint gid = get_global_id(0);
  const int count = *path_count;
  const uint n = count <= 0 ? 0u : min((uint)count, path_capacity);
  if (n == 0) {
    if (gid == 0) {
      offsets[texel_count] = 0;
      *active_count_out = 0;
    }
    return;
  }
  if (gid >= n) return;

  const uint next_path = gid + 1;
  const uint previous = sorted_texels[gid];
  /* Invalid texels and the end of the paths both read as texel_count. */
  const uint current = next_path == n ? texel_count : min(sorted_texels[next_path], texel_count);

  /* No earlier work-item sees the start of the first path's texel. */
  if (gid == 0) {
    if (previous < texel_count) {
      offsets[previous] = 0;
    } else { /* sorted: no path is valid */
      offsets[texel_count] = 0;
      *active_count_out = 0;
    }
  }
  if (previous < texel_count && previous < current) {
    /* previous + 1 <= texel_count: the extra entry takes the end of the last
     * valid texel. */
    offsets[previous + 1] = next_path;
    if (current < texel_count) {
      offsets[current] = next_path;
    } else { /* the only valid -> invalid (or end) transition */
      offsets[texel_count] = next_path;
      *active_count_out = (int)next_path;
    }
  }
}

/* Expands the offset buffer through lux_offset_range: ranges[t] = (first,
 * end), (0, 0) for a texel without paths. For tests and debugging dumps;
 * the accumulation kernels call lux_offset_range directly. */
__kernel void offset_read_ranges(__global const uint* offsets, const uint texel_count,
                                 __global uint2* ranges) {
  const uint texel = get_global_id(0);
  if (texel >= texel_count) return;
  uint first, end;
  (void)lux_offset_range(offsets, texel, texel_count, &first, &end);
  ranges[texel] = (uint2)(first, end);
}
