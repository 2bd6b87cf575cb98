/* Test-only kernels: expose the shading device functions (shading/lights.h,
 * shading/texture.h, shading/distribution.h) to host tests one call per
 * work-item. Not used by the bake. Buffers of absent features may be null. */

#include "shading/lights.h"
#include "shading/texture.h"

/* lux_sample_light at points[i].xyz with normal normals[i].xyz and randoms[i]
 * = (u_select, u.x, u.y). out_wi_pdf: wi, pdf (pdf 0 when nothing was sampled).
 * out_radiance_dist: radiance, dist. out_info: light, triangle,
 * is_delta | mis << 1, returned value. */
__kernel void probe_sample_lights(
    __global const LuxLight* lights, __global const LuxAliasEntry* light_select,
    const uint light_count, const LuxSky sky, __global const float* sky_texels,
    __global const float* sky_block_cdfs, __global const float* sky_texel_cdfs,
    __global const float4* points, __global const float4* normals, __global const float4* randoms,
    const int count, __global float4* out_wi_pdf, __global float4* out_radiance_dist,
    __global int4* out_info, __global float2* out_bary) {
  const int i = (int)get_global_id(0);
  if (i >= count) return;
  const float4 r = randoms[i];
  LuxLightSample s;
  const int ok =
      lux_sample_light(lights, light_select, light_count, sky, sky_texels, sky_block_cdfs,
                       sky_texel_cdfs, points[i].xyz, normals[i].xyz, r.x, r.yz, &s);
  out_wi_pdf[i] = ok ? (float4)(s.wi, s.pdf) : (float4)(0.0f);
  out_radiance_dist[i] = ok ? (float4)(s.radiance, s.dist) : (float4)(0.0f);
  out_info[i] = (int4)(s.light, s.triangle, s.is_delta | (s.mis << 1), ok);
  out_bary[i] = ok ? s.bary : (float2)(0.0f);
}

/* lux_light_pdf_triangle for (light[i], p[i], hit[i], normal[i]). */
__kernel void probe_triangle_pdf(__global const LuxLight* lights,
                                 __global const LuxAliasEntry* light_select,
                                 __global const int* light, __global const float4* p,
                                 __global const float4* hit, __global const float4* normal,
                                 const int count, __global float* out) {
  const int i = (int)get_global_id(0);
  if (i >= count) return;
  out[i] =
      lux_light_pdf_triangle(lights, light_select, light[i], p[i].xyz, hit[i].xyz, normal[i].xyz);
}

/* lux_sky_radiance and lux_sky_pdf along dirs[i] from a point with normal n:
 * out = radiance, pdf. */
__kernel void probe_sky(const LuxSky sky, __global const float* sky_texels,
                        __global const LuxAliasEntry* light_select, const int sky_light,
                        __global const float* sky_block_cdfs, __global const float* sky_texel_cdfs,
                        __global const float4* dirs, const int count, const float4 n,
                        __global float4* out) {
  const int i = (int)get_global_id(0);
  if (i >= count) return;
  const float3 d = dirs[i].xyz;
  out[i] =
      (float4)(lux_sky_radiance(sky, sky_texels, d),
               lux_sky_pdf(sky, light_select, sky_light, sky_block_cdfs, sky_texel_cdfs, d, n.xyz));
}

/* lux_sample_cdf over n cells for u[i]. */
__kernel void probe_sample_cdf(__global const float* cdf, const uint n, __global const float* u,
                               const int count, __global int* index, __global float* pmf) {
  const int i = (int)get_global_id(0);
  if (i >= count) return;
  float p;
  index[i] = (int)lux_sample_cdf(cdf, n, u[i], &p);
  pmf[i] = p;
}

/* lux_texture_slot_sample of material slot `slot` at UV sets (uv0[i], uv1[i]). */
__kernel void probe_texture(__global const uint* texels, __global const LuxTexture* textures,
                            const LuxTextureSlot slot, __global const float2* uv0,
                            __global const float2* uv1, const int count, __global float4* out) {
  const int i = (int)get_global_id(0);
  if (i >= count) return;
  out[i] = lux_texture_slot_sample(texels, textures, slot, uv0[i], uv1[i]);
}

/* lux_sample_alias over an n-entry table for u[i]. */
__kernel void probe_sample_alias(__global const LuxAliasEntry* table, const uint n,
                                 __global const float* u, const int count, __global int* index,
                                 __global float* pmf) {
  const int i = get_global_id(0);
  if (i >= count) return;
  float p;
  index[i] = (int)lux_sample_alias(table, n, u[i], &p);
  pmf[i] = p;
}
