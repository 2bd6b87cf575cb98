/* Ray queries over the BVH: closest hit and any hit.
 *
 * Both kernels read the live ray count from a device buffer (DESIGN.md: live
 * counts stay on the device) and are launched over the ray buffer's capacity;
 * work-items past the count return at once.
 *
 * Features (-D from the FeatureSet):
 *   LUX_ALPHA_MASK  the scene has alphaMode MASK triangles: candidate hits on
 *                   masked triangles run the shared alpha test. Without it
 *                   the alpha buffers are not even arguments' targets. */

#include "intersect/traverse.h"
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

/* Traverses for ray `ray`; writes the closest (or any) hit. Returns the
 * original triangle id or -1. */
inline int lux_trace(__global const LuxBvhNode* nodes,
                     __global const LuxTriangle* tris LUX_ALPHA_PARAMS, const LuxRay ray,
                     int any_hit, float* t_out, float* u_out, float* v_out) {
  const float3 org = ray.org_tmin.xyz;
  const float3 dir = ray.dir_tmax.xyz;
  const float tmin = ray.org_tmin.w;
  float t_best = ray.dir_tmax.w;
  const float3 inv_dir = lux_safe_inv_dir(dir);
  const LuxRayShear shear = lux_ray_shear(org, dir);

  int hit_prim = -1;
  float hit_u = 0.0f, hit_v = 0.0f;
  int stack_node[LUX_STACK_SIZE];
  float stack_t[LUX_STACK_SIZE];
  int sp = 0;
  int node = 0;

  for (;;) {
    const LuxBvhNode n = nodes[node];
    float tl = lux_box_entry(n.lmin, n.lmax, org, inv_dir, tmin, t_best);
    float tr = lux_box_entry(n.rmin, n.rmax, org, inv_dir, tmin, t_best);
    const int lref = as_int(n.lmin.w), lcount = as_int(n.lmax.w);
    const int rref = as_int(n.rmin.w), rcount = as_int(n.rmax.w);
    /* An absent child (ref -1) is never entered: the slab test alone would
     * accept its inverted bounds. */
    if (lref < 0) tl = INFINITY;
    if (rref < 0) tr = INFINITY;

    /* Leaves are tested in place, nearer first. */
    const int first_left = tl <= tr;
    for (int side = 0; side < 2; ++side) {
      const int left = (side == 0) == first_left;
      const int count = left ? lcount : rcount;
      const float entry = left ? tl : tr;
      if (count == 0 || !(entry <= t_best) || entry == INFINITY) continue;
      const int first = left ? lref : rref;
      for (int i = first; i < first + count; ++i) {
        const LuxTriangle tri = tris[i];
        float t = t_best, u, v;
        if (lux_intersect_triangle(&shear, tri.v0.xyz, tri.v1.xyz, tri.v2.xyz, tmin, &t, &u, &v) &&
            LUX_ALPHA_ACCEPT(i, tri, u, v)) {
          t_best = t;
          hit_u = u;
          hit_v = v;
          hit_prim = as_int(tri.v0.w);
          if (any_hit) {
            *t_out = t_best;
            return hit_prim;
          }
        }
      }
      if (left)
        tl = INFINITY;
      else
        tr = INFINITY;
    }

    /* INFINITY marks a missed (or already tested leaf) child; t_best may
     * itself be INFINITY before the first hit. */
    const int go_l = tl < INFINITY && tl <= t_best;
    const int go_r = tr < INFINITY && tr <= t_best;
    if (go_l && go_r) {
      const int near_left = tl <= tr;
      if (sp < LUX_STACK_SIZE) {
        stack_node[sp] = near_left ? rref : lref;
        stack_t[sp] = near_left ? tr : tl;
        ++sp;
      }
      node = near_left ? lref : rref;
      continue;
    }
    if (go_l) {
      node = lref;
      continue;
    }
    if (go_r) {
      node = rref;
      continue;
    }
    /* Pop, skipping subtrees that start behind the closest hit. */
    node = -1;
    while (sp > 0) {
      --sp;
      if (stack_t[sp] <= t_best) {
        node = stack_node[sp];
        break;
      }
    }
    if (node < 0) break;
  }
  *t_out = t_best;
  *u_out = hit_u;
  *v_out = hit_v;
  return hit_prim;
}

#if LUX_ALPHA_MASK
#define LUX_ALPHA_ARGS , tri_uvs, masks, alpha_texels
#else
#define LUX_ALPHA_ARGS
#endif

/* Closest hit of one ray as a LuxHit (prim -1 on a miss). */
inline LuxHit lux_closest_hit(__global const LuxBvhNode* nodes,
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
inline int lux_occluded(__global const LuxBvhNode* nodes,
                        __global const LuxTriangle* tris LUX_ALPHA_PARAMS, const LuxRay ray) {
  float t, u, v;
  return lux_trace(nodes, tris LUX_ALPHA_ARGS, ray, 1, &t, &u, &v) >= 0 ? 1 : 0;
}

__kernel void intersect_closest(__global const LuxBvhNode* nodes,
                                __global const LuxTriangle* tris LUX_ALPHA_PARAMS,
                                __global const LuxRay* rays, __global const int* ray_count,
                                __global LuxHit* hits) {
  const int gid = (int)get_global_id(0);
  if (gid >= *ray_count) return;
  hits[gid] = lux_closest_hit(nodes, tris LUX_ALPHA_ARGS, rays[gid]);
}

__kernel void intersect_any(__global const LuxBvhNode* nodes,
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
__kernel void intersect_closest_indexed(__global const LuxBvhNode* nodes,
                                        __global const LuxTriangle* tris LUX_ALPHA_PARAMS,
                                        __global const LuxRay* rays, __global const uint* indices,
                                        __global const int* ray_count, uint index_mask,
                                        __global LuxHit* hits) {
  const int gid = (int)get_global_id(0);
  if (gid >= *ray_count) return;
  const uint r = indices[gid] & index_mask;
  hits[r] = lux_closest_hit(nodes, tris LUX_ALPHA_ARGS, rays[r]);
}

__kernel void intersect_any_indexed(__global const LuxBvhNode* nodes,
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
