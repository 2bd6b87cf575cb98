/* Surface points of the bake: a triangle's interpolated position, normals and
 * material UV, the material's normal map, and ray offsets. Device only. */
#ifndef LUXEL_BAKE_SURFACE_H
#define LUXEL_BAKE_SURFACE_H

#include "shading/texture.h"
#include "shared/bake.h"
#include "shared/geometry.h"
#include "shared/ray_offset.h"

typedef struct LuxSurface {
  float3 p;        /* world position */
  float3 ng;       /* unit geometric normal, on the shading normal's side */
  float3 ng_front; /* unit geometric normal of the front face (emitter front side) */
  float3 ns;       /* unit shading normal, on the same side as ng (normal-mapped
                      after lux_surface_normal_map) */
  float2 uv;       /* material UV set 0 (TEXCOORD_0) */
  float2 uv1;      /* material UV set 1 (TEXCOORD_1) with LUX_TEXCOORD1, else uv */
  int material;
  int light; /* emissive light index or -1 */
} LuxSurface;

/* Barycentrics (b1, b2) weight vertices 1 and 2, as in LuxHit.u/v. */
inline LuxSurface lux_surface_at(const __global LuxSurfaceTri* tris, int tri, float b1, float b2) {
  const LuxSurfaceTri t = tris[tri];
  const float b0 = 1.0f - b1 - b2;
  LuxSurface s;
  s.p = b0 * t.p0.xyz + b1 * t.p1.xyz + b2 * t.p2.xyz;
  const float3 cross_e = cross(t.p1.xyz - t.p0.xyz, t.p2.xyz - t.p0.xyz);
  const float len = length(cross_e);
  s.ng = len > 0.0f ? cross_e / len : (float3)(0.0f, 1.0f, 0.0f);
  /* glTF 2.0 §3.7.4: the front face is the counter-clockwise one, unless
   * the instance transform mirrors (negative determinant): then it is the
   * clockwise one, and t.front = -1 (kernels/shared/bake.h). */
  s.ng_front = t.front < 0.0f ? -s.ng : s.ng;
  float3 ns = b0 * t.n0.xyz + b1 * t.n1.xyz + b2 * t.n2.xyz;
  const float ns_len = length(ns);
  ns = ns_len > 1e-20f ? ns / ns_len : s.ng;
  /* Winding and vertex normals disagree on a few real-world triangles
   * (scenes/README: 99.86-99.99 % agree): trust the vertex normals for the
   * side, so the geometric normal follows the shading normal. */
  if (dot(ns, s.ng) < 0.0f) s.ng = -s.ng;
  s.ns = ns;
  s.uv = b0 * (float2)(t.uv0.x, t.uv0.y) + b1 * (float2)(t.uv1.x, t.uv1.y) +
         b2 * (float2)(t.uv2.x, t.uv2.y);
  s.uv1 = s.uv;
  s.material = as_int(t.p0.w);
  s.light = as_int(t.p1.w);
  return s;
}

/* Material UV set 1 of triangle tri at (b1, b2), from the per-triangle
 * buffer that exists only when a material reads TEXCOORD_1 (LUX_TEXCOORD1). */
inline float2 lux_surface_uv1(const __global LuxTriangleUV* uvs, int tri, float b1, float b2) {
  const LuxTriangleUV t = uvs[tri];
  const float b0 = 1.0f - b1 - b2;
  return b0 * (float2)(t.uv0.x, t.uv0.y) + b1 * (float2)(t.uv1.x, t.uv1.y) +
         b2 * (float2)(t.uv2.x, t.uv2.y);
}

#if LUX_NORMAL_MAP
/* Vertex tangent of triangle tri at (b1, b2), interpolated (w: the sign of
 * the interpolated bitangent sign; constant over a triangle in practice). */
inline float4 lux_surface_tangent(const __global LuxTriangleTangents* tangents, int tri, float b1,
                                  float b2) {
  const LuxTriangleTangents t = tangents[tri];
  return (1.0f - b1 - b2) * t.t0 + b1 * t.t1 + b2 * t.t2;
}

/* Applies material m's normal map to s->ns (shading/texture.h), in the
 * surface's own frame (before any flip toward the viewer). The geometric
 * normal stays as it is: ray offsets and the hemisphere test use it. */
inline void lux_surface_normal_map(LuxSurface* s, const LuxMaterial* m,
                                   const __global LuxTexture* textures, const __global uint* texels,
                                   const __global LuxTriangleTangents* tangents, int tri, float b1,
                                   float b2) {
  if (m->normal_tex.texture < 0) return;
  const float3 rgb = lux_texture_slot_sample(texels, textures, m->normal_tex, s->uv, s->uv1).xyz;
  s->ns = lux_normal_map_perturb(s->ns, s->ng, lux_surface_tangent(tangents, tri, b1, b2), rgb,
                                 m->normal_scale);
}
#endif

/* The robust offset of kernels/shared/ray_offset.h (Wächter & Binder) with
 * its near-origin constants scaled by the scene size (`scale` = the scene's
 * largest extent, clamped to <= 1): the fixed float offset (1/65536) near the
 * origin was 1.5 % of a 1e-3-unit room and biased its lighting. Scenes of
 * unit size and larger get exactly the shared offset. */
inline float lux_offset_component_scaled(float p, float n, float scale) {
  const int of_i = (int)(LUX_OFFSET_INT_SCALE * n);
  const float p_i = as_float(as_int(p) + ((p < 0.0f) ? -of_i : of_i));
  return (fabs(p) < LUX_OFFSET_ORIGIN * scale) ? p + LUX_OFFSET_FLOAT_SCALE * scale * n : p_i;
}

/* Offsets p off the surface to the side `dir` leaves from. */
inline float3 lux_offset_origin(float3 p, float3 ng, float3 dir, float scale) {
  const float3 n = dot(dir, ng) >= 0.0f ? ng : -ng;
  return (float3)(lux_offset_component_scaled(p.x, n.x, scale),
                  lux_offset_component_scaled(p.y, n.y, scale),
                  lux_offset_component_scaled(p.z, n.z, scale));
}

#endif /* LUXEL_BAKE_SURFACE_H */
