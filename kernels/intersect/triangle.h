/* Watertight ray-triangle intersection.
 *
 * Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection" (JCGT 2(1),
 * 2013): the ray is transformed so its direction is +z (axis permutation plus
 * shear), the triangle's vertices are projected, and the 2-D edge functions
 * decide inclusion. Edges shared by two triangles are evaluated identically
 * for both, so a ray never slips between them; edge functions that come out
 * exactly zero are recomputed in double when the device supports it. */
#ifndef LUXEL_INTERSECT_TRIANGLE_H
#define LUXEL_INTERSECT_TRIANGLE_H

#include "shared/geometry.h"

#ifdef cl_khr_fp64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#define LUX_HAVE_FP64 1
#endif

/* Per-ray constants of the watertight test (computed once per ray). */
typedef struct {
  float3 org;
  int kx, ky, kz;
  float sx, sy, sz;
} LuxRayShear;

inline LuxRayShear lux_ray_shear(float3 org, float3 dir) {
  LuxRayShear s;
  s.org = org;
  const float3 a = fabs(dir);
  /* kz: dimension where the direction is largest in magnitude. */
  int kz = (a.x > a.y) ? ((a.x > a.z) ? 0 : 2) : ((a.y > a.z) ? 1 : 2);
  int kx = kz + 1 == 3 ? 0 : kz + 1;
  int ky = kx + 1 == 3 ? 0 : kx + 1;
  const float dk[3] = {dir.x, dir.y, dir.z};
  /* Swap kx and ky to preserve the winding of the triangle. */
  if (dk[kz] < 0.0f) {
    const int t = kx;
    kx = ky;
    ky = t;
  }
  s.kx = kx;
  s.ky = ky;
  s.kz = kz;
  s.sx = dk[kx] / dk[kz];
  s.sy = dk[ky] / dk[kz];
  s.sz = 1.0f / dk[kz];
  return s;
}

inline float lux_component(float3 v, int k) {
  return k == 0 ? v.x : (k == 1 ? v.y : v.z);
}

/* Tests one triangle; on a hit with t in (tmin, *t_best) updates *t_best,
 * *u, *v and returns 1. u, v are the barycentrics of v1 and v2. */
inline int lux_intersect_triangle(const LuxRayShear* r, float3 v0, float3 v1, float3 v2, float tmin,
                                  float* t_best, float* u_out, float* v_out) {
  const float3 A3 = v0 - r->org;
  const float3 B3 = v1 - r->org;
  const float3 C3 = v2 - r->org;
  const float Az = lux_component(A3, r->kz), Bz = lux_component(B3, r->kz),
              Cz = lux_component(C3, r->kz);
  const float Ax = lux_component(A3, r->kx) - r->sx * Az;
  const float Ay = lux_component(A3, r->ky) - r->sy * Az;
  const float Bx = lux_component(B3, r->kx) - r->sx * Bz;
  const float By = lux_component(B3, r->ky) - r->sy * Bz;
  const float Cx = lux_component(C3, r->kx) - r->sx * Cz;
  const float Cy = lux_component(C3, r->ky) - r->sy * Cz;

  float U = Cx * By - Cy * Bx;
  float V = Ax * Cy - Ay * Cx;
  float W = Bx * Ay - By * Ax;
#if LUX_HAVE_FP64
  if (U == 0.0f || V == 0.0f || W == 0.0f) {
    U = (float)((double)Cx * (double)By - (double)Cy * (double)Bx);
    V = (float)((double)Ax * (double)Cy - (double)Ay * (double)Cx);
    W = (float)((double)Bx * (double)Ay - (double)By * (double)Ax);
  }
#endif
  /* Back- and front-facing triangles are both hit (no culling). */
  if ((U < 0.0f || V < 0.0f || W < 0.0f) && (U > 0.0f || V > 0.0f || W > 0.0f)) return 0;
  const float det = U + V + W;
  if (det == 0.0f) return 0;
  const float T = U * r->sz * Az + V * r->sz * Bz + W * r->sz * Cz;
  /* Compare T against the interval scaled by det without dividing; the sign
   * of det flips the comparisons. */
  const float abs_det = fabs(det);
  const float signed_T = (det < 0.0f) ? -T : T;
  if (signed_T <= tmin * abs_det || signed_T >= *t_best * abs_det) return 0;
  const float inv_det = 1.0f / det;
  const float t = T * inv_det;
  if (t <= tmin || t >= *t_best) return 0;
  *t_best = t;
  *u_out = V * inv_det;
  *v_out = W * inv_det;
  return 1;
}

#endif /* LUXEL_INTERSECT_TRIANGLE_H */
