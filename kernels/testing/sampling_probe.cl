/* Probe kernels for tests/unit/kernels/sampling: evaluate the device sampling
 * functions for batches of inputs so the host can check them statistically.
 * Not used by the renderer. Build with LUX_SPECULAR and/or
 * LUX_SEQUENCE_RANDOM to probe those variants. */

#include "sampling/sequence.h"
#include "sampling/warp.h"
#include "shading/bsdf.h"

/* query = (index, dimension, seed, arity 1 or 2); 1D results leave y = 0. */
__kernel void probe_sequence(__global const uint4* queries, const uint count,
                             __global float2* out) {
  const uint i = get_global_id(0);
  if (i >= count) return;
  const uint4 q = queries[i];
  out[i] = q.w == 1u ? (float2)(lux_sample_1d(q.x, q.y, q.z), 0.0f) : lux_sample_2d(q.x, q.y, q.z);
}

__kernel void probe_hash(__global const uint* in, const uint count, __global uint* out) {
  const uint i = get_global_id(0);
  if (i >= count) return;
  out[i] = lux_hash_u32(in[i]);
}

#if !LUX_SEQUENCE_RANDOM /* the Sobol build only */
__kernel void probe_sobol_dim1(__global const uint* in, const uint count, __global uint* out) {
  const uint i = get_global_id(0);
  if (i >= count) return;
  out[i] = lux_sobol_dim1(in[i]);
}
#endif

/* Warps, selected by `warp`. out = (point, density at the point):
 *   0 cosine hemisphere   1 uniform hemisphere   2 uniform sphere (w = 0)
 *   3 uniform cone(param = cos_max)              4 triangle: (b1, b2, 0, 0) */
__kernel void probe_warp(__global const float4* u, const uint count, const int warp,
                         const float param, __global float4* out) {
  const uint i = get_global_id(0);
  if (i >= count) return;
  const float2 uv = u[i].xy;
  float4 r = (float4)(0.0f);
  if (warp == 0) {
    const float3 d = lux_cosine_hemisphere(uv);
    r = (float4)(d, lux_cosine_hemisphere_pdf(d.z));
  } else if (warp == 1) {
    r = (float4)(lux_uniform_hemisphere(uv), lux_uniform_hemisphere_pdf());
  } else if (warp == 2) {
    r = (float4)(lux_uniform_sphere(uv), 0.0f);
  } else if (warp == 3) {
    r = (float4)(lux_uniform_cone(uv, param), lux_uniform_cone_pdf(param));
  } else if (warp == 4) {
    r = (float4)(lux_uniform_triangle(uv), 0.0f, 0.0f);
  }
  out[i] = r;
}

/* lux_cosine_hemisphere_pdf at given directions. */
__kernel void probe_cosine_hemisphere_pdf(__global const float4* dirs, const uint count,
                                          __global float* out) {
  const uint i = get_global_id(0);
  if (i >= count) return;
  out[i] = lux_cosine_hemisphere_pdf(dirs[i].z);
}

/* out[4i..4i+3] = t, b, to_world(v), to_local(to_world(v)). */
__kernel void probe_onb(__global const float4* normals, __global const float4* vectors,
                        const uint count, __global float4* out) {
  const uint i = get_global_id(0);
  if (i >= count) return;
  const float3 n = normals[i].xyz;
  float3 t, b;
  lux_onb(n, &t, &b);
  const float3 w = lux_to_world(vectors[i].xyz, t, b, n);
  out[4 * i + 0] = (float4)(t, 0.0f);
  out[4 * i + 1] = (float4)(b, 0.0f);
  out[4 * i + 2] = (float4)(w, 0.0f);
  out[4 * i + 3] = (float4)(lux_to_local(w, t, b, n), 0.0f);
}

/* material = (base_color, metallic), rough[i] = (roughness, wo.z; 0 means 1,
 * dielectric f0; 0 means 0.04).
 * out[3i] = (diffuse, alpha), out[3i+1] = (f0, p_specular),
 * out[3i+2] = (ms, p_cosine): ms = f_ms / (1 - E(wi.z)). */
__kernel void probe_make_bsdf(__global const float4* material, __global const float4* rough,
                              const uint count, __global float4* out) {
  const uint i = get_global_id(0);
  if (i >= count) return;
  const LuxBsdf m = lux_make_bsdf(material[i].xyz, material[i].w, rough[i].x,
                                  (float3)(rough[i].z > 0.0f ? rough[i].z : LUX_BSDF_DIELECTRIC_F0),
                                  1.0f, rough[i].y > 0.0f ? rough[i].y : 1.0f);
  out[3 * i + 0] = (float4)(m.diffuse, m.alpha);
  out[3 * i + 1] = (float4)(m.f0, m.p_specular);
  out[3 * i + 2] = (float4)(m.ms, m.p_cosine);
}

/* lux_bsdf_sample for one material and wo; u[i] = (u.x, u.y, u_layer, -).
 * A u_layer_override >= 0 replaces every u_layer (0 forces the specular
 * layer when p_specular > 0). wo4.w: the dielectric f0 (0 means 0.04);
 * spec: (dielectric f0 rgb, f90) replacing it when spec.w > 0
 * (KHR_materials_specular).
 *   sample[i] = (wi, layer)            weight[i] = (weight, pdf)
 *   check[i]  = (f_layer(wi) cos / pdf, lux_bsdf_pdf_layer(layer, wi))   (0 for -1) */
__kernel void probe_bsdf_sample(const float4 material, const float roughness, const float4 wo4,
                                const float4 spec, const float u_layer_override,
                                __global const float4* u, const uint count, __global float4* sample,
                                __global float4* weight, __global float4* check) {
  const uint i = get_global_id(0);
  if (i >= count) return;
  const float f0 = wo4.w > 0.0f ? wo4.w : LUX_BSDF_DIELECTRIC_F0;
  const LuxBsdf m =
      lux_make_bsdf(material.xyz, material.w, roughness, spec.w > 0.0f ? spec.xyz : (float3)(f0),
                    spec.w > 0.0f ? spec.w : 1.0f, wo4.z);
  const float3 wo = wo4.xyz;
  const float4 ui = u[i];
  float3 wi = (float3)(0.0f), w;
  float pdf;
  const int layer = lux_bsdf_sample(&m, wo, u_layer_override >= 0.0f ? u_layer_override : ui.z,
                                    ui.xy, &wi, &w, &pdf);
  sample[i] = (float4)(wi, (float)layer);
  weight[i] = (float4)(w, pdf);
  float4 c = (float4)(0.0f);
  if (layer >= 0) {
    const float p = lux_bsdf_pdf_layer(&m, layer, wo, wi);
    c = (float4)(lux_bsdf_eval_layer(&m, layer, wo, wi) * wi.z / pdf, p);
  }
  check[i] = c;
}

/* Both layers at given directions: out[2i] = (f_diffuse, pdf_diffuse),
 * out[2i+1] = (f_specular, pdf_specular). */
__kernel void probe_bsdf_eval(const float4 material, const float roughness, const float4 wo4,
                              const float4 spec, __global const float4* dirs, const uint count,
                              __global float4* out) {
  const uint i = get_global_id(0);
  if (i >= count) return;
  const float f0 = wo4.w > 0.0f ? wo4.w : LUX_BSDF_DIELECTRIC_F0;
  const LuxBsdf m =
      lux_make_bsdf(material.xyz, material.w, roughness, spec.w > 0.0f ? spec.xyz : (float3)(f0),
                    spec.w > 0.0f ? spec.w : 1.0f, wo4.z);
  const float3 wo = wo4.xyz, wi = dirs[i].xyz;
  for (int layer = 0; layer < 2; ++layer)
    out[2 * i + layer] =
        (float4)(lux_bsdf_eval_layer(&m, layer, wo, wi), lux_bsdf_pdf_layer(&m, layer, wo, wi));
}
