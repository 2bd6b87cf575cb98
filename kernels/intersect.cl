/* Ray queries over the BVH: closest hit and any hit.
 *
 * Both kernels read the live ray count from a device buffer (DESIGN.md: live
 * counts stay on the device) and are launched over the ray buffer's capacity;
 * work-items past the count return at once.
 *
 * Features: -D options from the tracer's FeatureSet, the ray-query group of
 * kernels/shared/features.h (LUX_ALPHA_MASK, LUX_BVH4, LUX_STACK_SIZE).
 * Without LUX_ALPHA_MASK the alpha buffers are not even arguments. */

#include "intersect/traverse.h"
#include "shared/features.h"
#include "shared/geometry.h"

#if LUX_ALPHA_MASK
#define LUX_ALPHA_PARAMS                                                       \
  , __global const LuxTriangleUV *tri_uvs, __global const LuxAlphaMask *masks, \
      __global const uchar *alpha_texels
#define LUX_ALPHA_ACCEPT(tri_index, tri, u, v) \
  (lux_as_int((tri).v1.w) < 0 ||               \
   lux_alpha_opaque(&tri_uvs[tri_index], &masks[lux_as_int((tri).v1.w)], alpha_texels, (u), (v)))
#else
#define LUX_ALPHA_PARAMS
#define LUX_ALPHA_ACCEPT(tri_index, tri, u, v) 1
#endif

/* The node layout is a FeatureSet choice per device (accel::preferred_bvh_width):
 * both define lux_trace() over their node type. */
#if LUX_BVH4
typedef LuxBvh4Node LuxNode;
#include "intersect/trace_bvh4.h"
#else
typedef LuxBvhNode LuxNode;
#include "intersect/trace_bvh2.h"
#endif

#if LUX_ALPHA_MASK
#define LUX_ALPHA_ARGS , tri_uvs, masks, alpha_texels
#else
#define LUX_ALPHA_ARGS
#endif

/* Closest hit of one ray as a LuxHit (prim -1 on a miss). */
inline LuxHit lux_closest_hit(__global const LuxNode* nodes,
                              __global const LuxTriangle* tris LUX_ALPHA_PARAMS, const LuxRay ray) {
  float t, u = 0.0f, v = 0.0f;
  LuxHit h;
  h.prim = lux_trace(nodes, tris LUX_ALPHA_ARGS, ray, 0, &t, &u, &v);
  h.t = t;
  h.u = u;
  h.v = v;
  return h;
}

/* 1 when anything blocks the ray within its interval. */
inline int lux_occluded(__global const LuxNode* nodes,
                        __global const LuxTriangle* tris LUX_ALPHA_PARAMS, const LuxRay ray) {
  float t, u, v;
  return lux_trace(nodes, tris LUX_ALPHA_ARGS, ray, 1, &t, &u, &v) >= 0 ? 1 : 0;
}

__kernel void intersect_closest(__global const LuxNode* nodes,
                                __global const LuxTriangle* tris LUX_ALPHA_PARAMS,
                                __global const LuxRay* rays, __global const int* ray_count,
                                __global LuxHit* hits) {
  const int gid = (int)get_global_id(0);
  if (gid >= *ray_count) return;
  hits[gid] = lux_closest_hit(nodes, tris LUX_ALPHA_ARGS, rays[gid]);
}

__kernel void intersect_any(__global const LuxNode* nodes,
                            __global const LuxTriangle* tris LUX_ALPHA_PARAMS,
                            __global const LuxRay* rays, __global const int* ray_count,
                            __global int* occluded) {
  const int gid = (int)get_global_id(0);
  if (gid >= *ray_count) return;
  occluded[gid] = lux_occluded(nodes, tris LUX_ALPHA_ARGS, rays[gid]);
}

/* Indexed variants for the wavefront bake (thesis §5.1, §5.4): work-item i
 * traces ray indices[i] & index_mask, so a compacted list of live paths (or a
 * list sorted by ray direction, with the octant in the bits above the mask)
 * drives traversal, and the result is written back at the SOURCE ray index so
 * rays and results stay in path order. */
__kernel void intersect_closest_indexed(__global const LuxNode* nodes,
                                        __global const LuxTriangle* tris LUX_ALPHA_PARAMS,
                                        __global const LuxRay* rays, __global const uint* indices,
                                        __global const int* ray_count, uint index_mask,
                                        __global LuxHit* hits) {
  const int gid = (int)get_global_id(0);
  if (gid >= *ray_count) return;
  const uint r = indices[gid] & index_mask;
  hits[r] = lux_closest_hit(nodes, tris LUX_ALPHA_ARGS, rays[r]);
}

__kernel void intersect_any_indexed(__global const LuxNode* nodes,
                                    __global const LuxTriangle* tris LUX_ALPHA_PARAMS,
                                    __global const LuxRay* rays, __global const uint* indices,
                                    __global const int* ray_count, uint index_mask,
                                    __global int* occluded) {
  const int gid = (int)get_global_id(0);
  if (gid >= *ray_count) return;
  const uint r = indices[gid] & index_mask;
  const LuxRay ray = rays[r];
  /* An empty interval (tmax < tmin) marks "no shadow ray": skip traversal. */
  occluded[r] = ray.dir_tmax.w > ray.org_tmin.w ? lux_occluded(nodes, tris LUX_ALPHA_ARGS, ray) : 0;
}
