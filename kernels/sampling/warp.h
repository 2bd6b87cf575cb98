/* Warps from the unit square [0,1)^2 to directions and triangle points, with
 * their densities. Directions are in a local frame whose z axis is the
 * normal; lux_onb / lux_to_world / lux_to_local move between frames.
 *
 * The maps are chosen to keep the stratification of the low-discrepancy
 * sequences of sampling/sequence.h (thesis §6.2): area-preserving and with
 * low distortion (concentric disk, Heitz's triangle map), so strata of the
 * square stay compact on the target domain. */
#ifndef LUXEL_SAMPLING_WARP_H
#define LUXEL_SAMPLING_WARP_H

#ifndef LUX_PI
#define LUX_PI 3.14159265358979323846f
#endif
#ifndef LUX_INV_PI
#define LUX_INV_PI 0.31830988618379067154f
#endif

/* (cos, sin) of 2 pi u, for u in [0, 1]. cospi/sinpi reduce their argument
 * exactly by integer steps; cos/sin of an angle past pi/4 take libm's general
 * argument reduction, which on PoCL was 3-4 % of a bake's time (perf,
 * __pocl_argReductionS). */
inline float2 lux_cos_sin_2pi(float u) {
  const float x = 2.0f * u;
  return (float2)(cospi(x), sinpi(x));
}

/* (cos, sin) of pi/4 q for q in [-1, 1]: Taylor series to x^8 and x^9
 * (x = pi/4 q), whose next terms are below 3e-8 on |x| <= pi/4, under an
 * ulp of the results. The general cospi/sinpi spend most of their ~60
 * instructions on argument reduction that this range does not need; the
 * concentric map below is on every cosine-weighted sample (the texel's first
 * direction, Lambertian lobes, the constant sky's light samples), and with
 * cospi/sinpi it was 6 % of a sky-lit bake (perf, lux_lights_sample_sky). */
inline float2 lux_cos_sin_quarter_pi(float q) {
  /* mad: fused where the device has FMA, and never a software fma. */
  const float x = (0.25f * LUX_PI) * q, x2 = x * x;
  float c = mad(x2, 2.4801587301587302e-5f, -1.3888888888888889e-3f);
  c = mad(x2, c, 4.1666666666666667e-2f);
  c = mad(x2, c, -0.5f);
  c = mad(x2, c, 1.0f);
  float s = mad(x2, 2.7557319223985891e-6f, -1.9841269841269841e-4f);
  s = mad(x2, s, 8.3333333333333333e-3f);
  s = mad(x2, s, -1.6666666666666667e-1f);
  s = mad(x2, s, 1.0f);
  return (float2)(c, x * s);
}

/* Shirley and Chiu's concentric map from the square to the unit disk
 * (pbrt-v3 §13.6.2): squares map to compact rings, unlike (sqrt(u), 2 pi v). */
inline float2 lux_concentric_disk(float2 u) {
  const float2 o = 2.0f * u - 1.0f;
  if (o.x == 0.0f && o.y == 0.0f) return (float2)(0.0f, 0.0f);
  /* The angle is pi/4 q or pi/2 - pi/4 q with |q| <= 1; the second as
   * (sin, cos) of pi/4 q, so every angle stays in [-pi/4, pi/4]. */
  if (fabs(o.x) > fabs(o.y)) {
    const float2 cs = lux_cos_sin_quarter_pi(o.y / o.x);
    return o.x * cs;
  }
  const float2 cs = lux_cos_sin_quarter_pi(o.x / o.y);
  return o.y * (float2)(cs.y, cs.x);
}

/* Cosine-weighted hemisphere (Malley's method: project the disk up, thesis
 * §6.3.1). Density cos(theta) / pi. */
inline float3 lux_cosine_hemisphere(float2 u) {
  const float2 d = lux_concentric_disk(u);
  const float z = sqrt(fmax(0.0f, 1.0f - d.x * d.x - d.y * d.y));
  return (float3)(d.x, d.y, z);
}

/* 0 below the horizon. */
inline float lux_cosine_hemisphere_pdf(float cos_theta) {
  return fmax(cos_theta, 0.0f) * LUX_INV_PI;
}

/* Uniform over the upper hemisphere: z = u.x. Density 1 / (2 pi). */
inline float3 lux_uniform_hemisphere(float2 u) {
  const float z = u.x;
  const float r = sqrt(fmax(0.0f, 1.0f - z * z));
  const float2 cs = lux_cos_sin_2pi(u.y);
  return (float3)(r * cs.x, r * cs.y, z);
}

inline float lux_uniform_hemisphere_pdf(void) {
  return 0.5f * LUX_INV_PI;
}

/* Uniform over the sphere: z = 1 - 2 u.x. Density 1 / (4 pi). */
inline float3 lux_uniform_sphere(float2 u) {
  const float z = 1.0f - 2.0f * u.x;
  const float r = sqrt(fmax(0.0f, 1.0f - z * z));
  const float2 cs = lux_cos_sin_2pi(u.y);
  return (float3)(r * cs.x, r * cs.y, z);
}

/* Uniform over the cone of directions with cos(theta) >= cos_max around +z
 * (cos_max in [-1, 1); -1 is the whole sphere). 1 - cos(theta) is formed
 * directly so small cones (cos_max near 1, e.g. the sun) keep precision. */
inline float3 lux_uniform_cone(float2 u, float cos_max) {
  const float one_minus_cos = u.x * (1.0f - cos_max);
  const float z = 1.0f - one_minus_cos;
  const float r = sqrt(fmax(0.0f, one_minus_cos * (2.0f - one_minus_cos)));
  const float2 cs = lux_cos_sin_2pi(u.y);
  return (float3)(r * cs.x, r * cs.y, z);
}

/* Density inside the cone (infinite for a degenerate cone, cos_max = 1). */
inline float lux_uniform_cone_pdf(float cos_max) {
  return 1.0f / (2.0f * LUX_PI * (1.0f - cos_max));
}

/* Area-uniform barycentrics (b1, b2) of a triangle (b0 = 1 - b1 - b2; the
 * point is b0 v0 + b1 v1 + b2 v2). Heitz, "A Low-Distortion Map Between
 * Triangle and Square" (2019): no square root, and nearby square points stay
 * nearby, unlike the sqrt fold of Osada et al. */
inline float2 lux_uniform_triangle(float2 u) {
  float b1, b2;
  if (u.y > u.x) {
    b1 = 0.5f * u.x;
    b2 = u.y - b1;
  } else {
    b2 = 0.5f * u.y;
    b1 = u.x - b2;
  }
  return (float2)(b1, b2);
}

/* Right-handed orthonormal basis (t, b, n) for a unit normal n, branchless
 * and continuous except across n.z = 0: Duff et al., "Building an
 * Orthonormal Basis, Revisited" (JCGT 6(1), 2017), Listing 3. */
inline void lux_onb(float3 n, float3* t, float3* b) {
  const float sign = copysign(1.0f, n.z);
  const float a = -1.0f / (sign + n.z);
  const float c = n.x * n.y * a;
  *t = (float3)(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
  *b = (float3)(c, sign + n.y * n.y * a, -n.y);
}

inline float3 lux_to_world(float3 v, float3 t, float3 b, float3 n) {
  return v.x * t + v.y * b + v.z * n;
}

inline float3 lux_to_local(float3 v, float3 t, float3 b, float3 n) {
  return (float3)(dot(v, t), dot(v, b), dot(v, n));
}

#endif /* LUXEL_SAMPLING_WARP_H */
