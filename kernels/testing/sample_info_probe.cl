/* Test probe for the sample-info buffer (thesis §4.3, Listing 4.2): decodes
 * (texel, rank) queries with the shared decoder exactly as ray generation
 * will, and reports the instance, mesh triangle, Hammersley index and the
 * sample's barycentrics in the decoded triangle, so a test can compare every
 * valid sample with the host decode.
 *
 *   offsets, words    the sample-info buffers
 *   queries           (texel, rank) per work-item
 *   triangle_base     per instance: index of its triangle 0 in triangle_uvs
 *   triangle_uvs      per world triangle: atlas UVs (u0, v0, u1, v1), (u2, v2, 0, 0)
 *   decoded           (instance, triangle, hammersley index, valid count)
 *   barycentrics      (w0, w1, w2, 0) of the sample in the decoded triangle */

#include "shared/sample_info.h"

__kernel void sample_info_probe(__global const uint* offsets, __global const uint* words,
                                __global const uint2* queries, __global const uint* triangle_base,
                                __global const float4* triangle_uvs, const uint width,
                                const uint height, const uint count, __global uint4* decoded,
                                __global float4* barycentrics) {
  const uint gid = (uint)get_global_id(0);
  if (gid >= count) return;
  const uint2 q = queries[gid];
  const uint offset = offsets[q.x];
  uint instance, triangle, index;
  lux_sample_info_lookup(words, offset, q.y, &instance, &triangle, &index);
  decoded[gid] = (uint4)(instance, triangle, index, lux_sample_info_count(words, offset));

  const uint world = triangle_base[instance] + triangle;
  const float4 a = triangle_uvs[2 * world];
  const float4 b = triangle_uvs[2 * world + 1];
  float w0, w1, w2;
  lux_texel_barycentrics(a.xy, a.zw, b.xy, (float)width, (float)height, q.x % width, q.x / width,
                         lux_hammersley64(index), &w0, &w1, &w2);
  barycentrics[gid] = (float4)(w0, w1, w2, 0.0f);
}
