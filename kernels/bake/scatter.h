/* Scattering at a path vertex: next-event estimation (thesis §6.1) and the
 * extension ray (BSDF importance sampling, §6.3.1, Eq. 6.2), with multiple
 * importance sampling (power heuristic) between the two strategies for lights
 * a BSDF ray can also hit (emissive triangles, the sky).
 *
 * Vertex 0 is the texel's surface point, a "sensor" rather than a material:
 * irradiance E = integral of L cos over the hemisphere, i.e. a BSDF f = 1
 * sampled with the cosine pdf cos/pi (§3.4: "the PDF ... cancels with the
 * Lambertian BRDF"; here the extension weight is cos / (cos/pi) = pi).
 *
 * Sample dimensions (§6.2, one progressive sequence per dimension): 0 picks
 * the texel's sample position; vertex k uses LUX_DIM_VERTEX(k) + 0..4. */
#ifndef LUXEL_BAKE_SCATTER_H
#define LUXEL_BAKE_SCATTER_H

#include "bake/surface.h"

#define LUX_DIM_TEXEL_SAMPLE 0u
#define LUX_DIM_VERTEX(k) (1u + 5u * (k))
#define LUX_DIM_LIGHT_SELECT 0u
#define LUX_DIM_LIGHT_POINT 1u
#define LUX_DIM_LAYER 2u
#define LUX_DIM_DIRECTION 3u
#define LUX_DIM_ROULETTE 4u

inline float lux_power_heuristic(float a, float b) {
  const float a2 = a * a, b2 = b * b;
  return a2 + b2 > 0.0f ? a2 / (a2 + b2) : 0.0f;
}

inline float lux_max3(float3 v) { return fmax(v.x, fmax(v.y, v.z)); }

inline int lux_finite3(float3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

/* A shadow ray that intersect_any_indexed skips (empty interval). */
inline LuxRay lux_no_ray(void) {
  LuxRay r;
  r.org_tmin = (float4)(0.0f, 0.0f, 0.0f, 1.0f);
  r.dir_tmax = (float4)(0.0f, 0.0f, 1.0f, -1.0f);
  return r;
}

inline LuxRay lux_make_ray(float3 org, float3 dir, float tmax) {
  LuxRay r;
  r.org_tmin = (float4)(org, 0.0f);
  r.dir_tmax = (float4)(dir, tmax);
  return r;
}

#if LUX_EMISSIVE_TEXTURE
/* Emitted radiance of a material at a surface UV (factor x texture). */
inline float3 lux_emission_at(const __global LuxMaterial* materials, int material, float2 uv,
                              const __global LuxTexture* textures, const __global uint* texels) {
  const LuxMaterial m = materials[material];
  float3 e = m.emission.xyz;
  if (m.emissive_tex >= 0) e *= lux_texture_sample(texels, textures[m.emissive_tex], uv).xyz;
  return e;
}
#endif

#endif /* LUXEL_BAKE_SCATTER_H */
