/* Structs of the ray-query interface, shared by host and device.
 *
 * BVH layout ("fat" BVH2, after RadeonRays 2.0): each node stores the bounds
 * of BOTH children, so traversal tests two boxes per node fetch and never
 * loads a child only to reject it. 64 bytes per node = one cache line.
 *
 *   lmin.xyz / lmax.xyz   bounds of the left child
 *   rmin.xyz / rmax.xyz   bounds of the right child
 *   lmin.w   (int) left child:  node index, or first triangle if lmax.w > 0
 *   lmax.w   (int) left child:  0 = inner node, n > 0 = leaf of n triangles
 *   rmin.w / rmax.w           the same for the right child
 *
 * Node 0 is the root. Leaves are not nodes: a child reference with count > 0
 * points straight at a contiguous range of LuxTriangle records (triangles are
 * reordered by the builder). An absent child (a scene with one leaf, or an
 * empty scene) has ref -1, count 0 and inverted bounds; traversal skips it
 * by its ref.
 *
 * BVH4 layout (LUX_BVH4; Ernst & Greiner 2008, "Multi Bounding Volume
 * Hierarchies"; Dammertz et al. 2008, "Shallow Bounding Volume Hierarchies
 * for Fast SIMD Ray Tracing of Incoherent Rays"): up to four children per
 * node, their bounds stored structure-of-arrays so one float4 holds the same
 * plane of all four boxes and traversal tests all four with float4 ops.
 * 128 bytes per node = two cache lines.
 *
 *   lo_x[i] .. hi_z[i]   bounds of child slot i
 *   child[i]             node index (count[i] == 0), first triangle of a
 *                        leaf (count[i] > 0), or -1 for an absent slot
 *   count[i]             0 = inner node, n > 0 = leaf of n triangles
 *
 * Node 0 is the root; children of a node are in no particular order (the
 * traversal sorts them by entry distance). Leaves are contiguous ranges of
 * LuxTriangle as in the BVH2 layout. An absent slot has bounds lo = hi =
 * +INFINITY on every axis: its entry distance is +INFINITY or the slab test
 * rejects it, so the traversal never enters it without testing the ref.
 */
#ifndef LUXEL_SHARED_GEOMETRY_H
#define LUXEL_SHARED_GEOMETRY_H

#include "shared/compat.h"

#ifndef LUX_DEVICE
namespace luxel::cl {
#endif

typedef struct LuxBvhNode {
  float4 lmin;
  float4 lmax;
  float4 rmin;
  float4 rmax;
} LuxBvhNode;

typedef struct LuxBvh4Node {
  float4 lo_x;
  float4 hi_x;
  float4 lo_y;
  float4 hi_y;
  float4 lo_z;
  float4 hi_z;
  int4 child;
  int4 count;
} LuxBvh4Node;

/* World-space triangle, 48 bytes.
 *   v0.w (int) original triangle id (index into the host's triangle soup,
 *        which maps to instance + mesh triangle)
 *   v1.w (int) alpha-mask id: -1 opaque, else index into LuxAlphaMask
 *   v2.w unused (0) */
typedef struct LuxTriangle {
  float4 v0;
  float4 v1;
  float4 v2;
} LuxTriangle;

/* A ray. tmin/tmax bound the parametric interval; dir need not be unit
 * length (t is in units of |dir|). 32 bytes. */
typedef struct LuxRay {
  float4 org_tmin; /* xyz origin, w tmin */
  float4 dir_tmax; /* xyz direction, w tmax */
} LuxRay;

/* Closest-hit result. prim = -1 on a miss; otherwise the ORIGINAL triangle id
 * (LuxTriangle.v0.w). u, v: barycentrics of v1 and v2. 16 bytes. */
typedef struct LuxHit {
  float t;
  float u;
  float v;
  int prim;
} LuxHit;

/* Alpha mask of one material texture (alphaMode MASK): 8-bit alpha texels in
 * one shared byte buffer, sampled nearest with repeat wrapping. */
typedef struct LuxAlphaMask {
  int offset; /* first byte in the alpha texel buffer */
  int width;
  int height;
  float cutoff; /* alphaCutoff / baseColorFactor.a, in [0, 1] texel units */
  int wrap;     /* the base colour sampler's wraps, LUX_SLOT_MAKE_WRAP(s, t) */
  int pad[3];
} LuxAlphaMask;

/* Per-triangle material UVs for alpha-tested triangles (indexed like
 * LuxTriangle, present only when the scene has alpha-masked geometry): the
 * base colour texture's UV set with its KHR_texture_transform applied per
 * vertex (the transform is affine, so it commutes with barycentric
 * interpolation). */
typedef struct LuxTriangleUV {
  float2 uv0;
  float2 uv1;
  float2 uv2;
  float2 pad;
} LuxTriangleUV;

#ifndef LUX_DEVICE
}  // namespace luxel::cl
#endif

#endif /* LUXEL_SHARED_GEOMETRY_H */
