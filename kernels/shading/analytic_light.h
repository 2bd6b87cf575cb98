/* Exact unshadowed irradiance at a receiver point from the lights whose
 * irradiance has a closed form (LUX_DIRECT_ANALYTIC, irradiance lightmaps):
 * uniformly emitting triangles through Lambert's polygon formula (support
 * thesis Eq. 2.21) after clipping to the receiver's horizon (§3.2.4, Alg. 5),
 * and punctual lights (point, spot, directional without angular radius), whose
 * irradiance is their radiance times the cosine.
 *
 * Emissive triangles with a texture, sun discs and the sky are not analytic:
 * they stay with plain next-event estimation.
 *
 * The receiver sees light only over directions above both its shading
 * normal's horizon (the cosine) and its geometric plane (lux_next_event drops
 * light samples below ng), so a triangle is clipped against both planes
 * before Lambert's formula; the result is then the exact integral of the very
 * integrand that lux_next_event samples, which the shadow estimator in
 * kernels/bake/raygen.h relies on. */
#ifndef LUXEL_SHADING_ANALYTIC_LIGHT_H
#define LUXEL_SHADING_ANALYTIC_LIGHT_H

#include "shading/lights.h"

/* 1 when light l's unshadowed irradiance is computed in closed form. */
inline int lux_light_is_analytic(const LuxLight* l) {
  switch (LUX_LIGHT_TYPE(*l)) {
    case LUX_LIGHT_TYPE_TRIANGLE:
      return !(LUX_LIGHT_FLAGS(*l) & LUX_LIGHT_FLAG_TEXTURED);
    case LUX_LIGHT_TYPE_POINT:
    case LUX_LIGHT_TYPE_SPOT:
      return 1;
    case LUX_LIGHT_TYPE_DIRECTIONAL:
      return !(LUX_LIGHT_ONE_MINUS_COS(*l) > 0.0f);
    default:
      return 0;
  }
}

/* Sutherland-Hodgman against the half-space dot(x, n) >= 0 of vertices
 * relative to the receiver (a plane through the receiver maps to a great
 * circle, so clipping the planar polygon clips its spherical projection, the
 * "ClipToHorizon" of Alg. 5). n_in vertices in v, at most n_in + 1 out. */
inline int lux_clip_to_plane(const float3* v, int n_in, float3 n, float3* out) {
  int n_out = 0;
  for (int i = 0; i < n_in; ++i) {
    const float3 a = v[i], b = v[(i + 1) % n_in];
    const float da = dot(a, n), db = dot(b, n);
    if (da >= 0.0f) out[n_out++] = a;
    if ((da >= 0.0f) != (db >= 0.0f)) {
      const float t = da / (da - db);
      out[n_out++] = a + (b - a) * t;
    }
  }
  return n_out;
}

/* Lambert's formula (Eq. 2.21 times pi, i.e. irradiance per unit radiance):
 * 1/2 sum_i angle(v_i, v_j) (v_i x v_j / |v_i x v_j|) . n over the polygon
 * edges, v relative to the receiver. The angle comes from atan2(|a x b|,
 * a . b), exact to float precision for the small angles of distant lights
 * where acos loses all digits. The sign follows the winding: the caller
 * takes the absolute value of one convex polygon. */
inline float lux_polygon_cosine_integral(const float3* v, int count, float3 n) {
  float sum = 0.0f;
  for (int i = 0; i < count; ++i) {
    const float3 a = normalize(v[i]), b = normalize(v[(i + 1) % count]);
    const float3 c = cross(a, b);
    const float s = length(c);
    if (!(s > 0.0f)) continue;
    sum += atan2(s, dot(a, b)) * dot(c, n) / s;
  }
  return 0.5f * sum;
}

#if LUX_LIGHT_EMISSIVE
/* Unshadowed irradiance from emissive-triangle light l at p (normals ns, ng). */
inline float3 lux_triangle_irradiance(const LuxLight* l, float3 p, float3 ns, float3 ng) {
  float3 v[3];
  v[0] = l->origin.xyz - p;
  v[1] = v[0] + l->axis.xyz;
  v[2] = v[0] + l->edge2.xyz;
  /* A one-sided emitter lights only its front half-space (the plane test of
   * lux_lights_sample_triangle, the same for every point of the triangle).
   * A receiver in the emitter's own plane (a texel on the emitter or on a
   * coplanar neighbour) sees it edge-on: nothing, which the sampled NEE
   * agrees with (cosine 0). It must be caught with a tolerance: the rounding
   * of v0 - p leaves it a few ulps above or below the plane, and Lambert's
   * formula for a polygon an ulp above a receiver inside it is pi L, the
   * limit of an emitter touching the receiver. The tolerance is relative to
   * the triangle's size and to the coordinates' magnitude (scale-free). */
  const float h = -dot(l->shape.xyz, v[0]); /* signed height of p over the emitter */
  const float3 ap = fabs(p);
  const float tol =
      1e-4f * sqrt(LUX_LIGHT_AREA(*l)) + 8.0f * FLT_EPSILON * fmax(ap.x, fmax(ap.y, ap.z));
  if (fabs(h) <= tol) return (float3)(0.0f);
  if (!(LUX_LIGHT_FLAGS(*l) & LUX_LIGHT_FLAG_DOUBLE_SIDED) && !(h > 0.0f)) return (float3)(0.0f);
  float3 c1[4], c2[5];
  const int n1 = lux_clip_to_plane(v, 3, ns, c1);
  if (n1 < 3) return (float3)(0.0f);
  const int n2 = lux_clip_to_plane(c1, n1, ng, c2);
  if (n2 < 3) return (float3)(0.0f);
  return l->emission.xyz * fabs(lux_polygon_cosine_integral(c2, n2, ns));
}
#endif

/* Unshadowed irradiance from analytic light l at p, or 0 for a light that is
 * not analytic. Punctual lights reuse their samplers (deterministic for
 * them), with lux_next_event's horizon tests. */
inline float3 lux_light_irradiance(const LuxLight* l, float3 p, float3 ns, float3 ng) {
  if (!lux_light_is_analytic(l)) return (float3)(0.0f);
  LuxLightSample s;
  s.is_delta = 0;
  s.mis = 0;
  int ok = 0;
  switch (LUX_LIGHT_TYPE(*l)) {
#if LUX_LIGHT_EMISSIVE
    case LUX_LIGHT_TYPE_TRIANGLE:
      return lux_triangle_irradiance(l, p, ns, ng);
#endif
#if LUX_LIGHT_POINT
    case LUX_LIGHT_TYPE_POINT:
      ok = lux_lights_sample_point(l, p, &s);
      break;
#endif
#if LUX_LIGHT_SPOT
    case LUX_LIGHT_TYPE_SPOT:
      ok = lux_lights_sample_spot(l, p, &s);
      break;
#endif
#if LUX_LIGHT_DIRECTIONAL
    case LUX_LIGHT_TYPE_DIRECTIONAL:
      ok = lux_lights_sample_directional(l, (float2)(0.0f), &s);
      break;
#endif
    default:
      break;
  }
  (void)p;
  if (!ok || dot(s.wi, ng) <= 0.0f) return (float3)(0.0f);
  const float cos_i = dot(s.wi, ns);
  return cos_i > 0.0f ? s.radiance * cos_i : (float3)(0.0f);
}

#endif /* LUXEL_SHADING_ANALYTIC_LIGHT_H */
