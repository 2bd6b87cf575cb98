/* Stack-based traversal of the fat BVH2 (kernels/shared/geometry.h).
 *
 * One work-item per ray (RadeonRays 2.0 `intersect_main` / `occluded_main`
 * style). Both child boxes are tested from one node fetch; the nearer child
 * is visited first and the farther pushed with its entry distance, which is
 * re-checked on pop so subtrees behind the current closest hit are skipped.
 *
 * Box tests are conservative (Ize, "Robust BVH Ray Traversal", JCGT 2(2),
 * 2013): the exit distance is scaled by 1 + 2 gamma(3) so rounding never
 * rejects a box the ray actually crosses, which together with the watertight
 * triangle test makes traversal watertight.
 *
 * Compiled twice from one source: LUX_ANY_HIT stops at the first accepted hit. */

#include "intersect/triangle.h"
#if LUX_ALPHA_MASK
#include "shared/alpha_mask.h"
#endif

#ifndef LUX_STACK_SIZE
#define LUX_STACK_SIZE 64
#endif

/* 1 + 2 * gamma(3), gamma(n) = n eps / (1 - n eps), eps = 2^-24. */
#define LUX_BOX_EXIT_SCALE 1.0000003576278687f

/* The triangles [first, first + count) of a leaf against the ray, shared by
 * both traversals (trace_bvh2.h, trace_bvh4.h). A macro over the caller's
 * names (tris, shear, tmin, t_best, hit_u, hit_v, hit_prim, any_hit, t_out)
 * and LUX_ALPHA_ACCEPT, so both compile to the loop they had inline: an
 * any-hit query returns from the caller at its first accepted hit. */
#define LUX_INTERSECT_LEAF(first, count)                                                        \
  for (int i = (first); i < (first) + (count); ++i) {                                           \
    const LuxTriangle tri = tris[i];                                                            \
    float t = t_best, u, v;                                                                     \
    if (lux_intersect_triangle(&shear, tri.v0.xyz, tri.v1.xyz, tri.v2.xyz, tmin, &t, &u, &v) && \
        LUX_ALPHA_ACCEPT(i, tri, u, v)) {                                                       \
      t_best = t;                                                                               \
      hit_u = u;                                                                                \
      hit_v = v;                                                                                \
      hit_prim = as_int(tri.v0.w);                                                              \
      if (any_hit) {                                                                            \
        *t_out = t_best;                                                                        \
        return hit_prim;                                                                        \
      }                                                                                         \
    }                                                                                           \
  }

inline float3 lux_safe_inv_dir(float3 d) {
  const float eps = 1e-20f;
  float3 s;
  s.x = fabs(d.x) < eps ? copysign(eps, d.x) : d.x;
  s.y = fabs(d.y) < eps ? copysign(eps, d.y) : d.y;
  s.z = fabs(d.z) < eps ? copysign(eps, d.z) : d.z;
  return 1.0f / s;
}

/* Entry distance of the ray into box [lo, hi], or INFINITY when it misses
 * the box within [tmin, tmax]. */
inline float lux_box_entry(float4 lo, float4 hi, float3 org, float3 inv_dir, float tmin,
                           float tmax) {
  const float3 t0 = (lo.xyz - org) * inv_dir;
  const float3 t1 = (hi.xyz - org) * inv_dir;
  const float3 tn = fmin(t0, t1);
  const float3 tf = fmax(t0, t1);
  const float enter = fmax(fmax(tn.x, tn.y), fmax(tn.z, tmin));
  const float exit = fmin(fmin(tf.x, tf.y), fmin(tf.z, tmax)) * LUX_BOX_EXIT_SCALE;
  return enter <= exit ? enter : INFINITY;
}
