/* Directional encodings in the gather accumulation (core thesis
 * §3.4 "Accumulation into Linear Bases", Ch. 7-8). Compiled only with
 * LUX_BASIS.
 *
 * Every path contributes one radiance sample: the radiance L arriving along
 * its first direction w (uniform over the hemisphere, pdf 1 / 2 pi), plus the
 * texel point's light sample, an unbiased estimate of the direct part of the
 * moments c_i = integral L B_i: nee * B_i(w_l) with nee = w_mis L_e / p_light
 * (delta lights: intensity / r^2 or the sun's irradiance, weight 1). The BSDF
 * half of that MIS pair is in L already (emission hit by the first segment).
 *
 * Solvers per encoding (LuxEncoding.solver):
 *  - projection: b_i = running mean of 2 pi B_i(w) L + nee B_i(w_l), the
 *    Monte Carlo moment ("naive projection", §7.2 footnote 2); the
 *    least-squares solution for orthonormal bases (SH).
 *  - progressive (non-negative): Listing 7.1 / Eq. 7.14-7.15 with
 *    Gauss-Seidel updates of delta (§7.3.1), exactly as the host reference
 *    encode::ProgressiveEncoder, plus the light sample's moment estimate
 *    added to the update numerator: the update's expectation is then
 *    alpha/k (c_i - (G b)_i) / G_ii as for a purely uniform sample stream.
 * State is fp32 (§7.3.2 warns against fp16). */
#ifndef LUXEL_BAKE_BASIS_H
#define LUXEL_BAKE_BASIS_H

#include "shared/bake.h"
#include "shared/bases.h"

#define LUX_TWO_PI_F 6.28318530717958647692f

/* The measure of the sampled domain and the scale of the light sample's
 * moment. Texels: the hemisphere (2 pi), light sample as is. Probes
 * (raygen.h): each path estimates the hemisphere of a random normal, twice
 * which is an unbiased estimate over the sphere, so first segments weigh
 * 4 pi (their directions are uniform over the sphere) and the light sample
 * twice. */
#if LUX_PROBES
#define LUX_BASIS_MEASURE (2.0f * LUX_TWO_PI_F)
#define LUX_BASIS_NEE_SCALE 2.0f
#define LUX_PROBE_DOMAIN 1
#else
#define LUX_PROBE_DOMAIN 0
#define LUX_BASIS_MEASURE LUX_TWO_PI_F
#define LUX_BASIS_NEE_SCALE 1.0f
#endif

/* The texel's tangent axis: the world direction of increasing lightmap u on
 * the triangle (dP/du from its atlas UVs), projected onto the tangent plane
 * of n. A triangle degenerate in UV space keeps `fallback`. */
inline float3 lux_lightmap_tangent(LuxSurfaceTri tri, LuxTriangleUV uvt, float3 n,
                                   float3 fallback) {
  const float3 e1 = tri.p1.xyz - tri.p0.xyz, e2 = tri.p2.xyz - tri.p0.xyz;
  const float du1 = uvt.uv1.x - uvt.uv0.x, dv1 = uvt.uv1.y - uvt.uv0.y;
  const float du2 = uvt.uv2.x - uvt.uv0.x, dv2 = uvt.uv2.y - uvt.uv0.y;
  const float det = du1 * dv2 - du2 * dv1;
  if (!(fabs(det) > 0.0f)) return fallback;
  const float3 dpdu = (e1 * dv2 - e2 * dv1) / det;
  const float3 tp = dpdu - n * dot(n, dpdu);
  const float len = length(tp);
  return len > 1e-12f && isfinite(len) ? tp / len : fallback;
}

/* B_0(d) .. B_{count-1}(d) of one encoding for a unit direction d in its frame. */
inline void lux_basis_eval(const LuxEncoding* e, __global const float4* dirs, float3 d,
                           float* out) {
  if (e->kind == LUX_ENC_SH) {
    lux_sh_eval(d.x, d.y, d.z, e->count, out);
    return;
  }
  for (int i = 0; i < e->count; ++i) {
    const float c = dot(dirs[e->first_dir + i].xyz, d);
    out[i] = e->kind == LUX_ENC_SG ? lux_sg_eval(c, e->sharpness) : lux_ad_cosine_lobe(c);
  }
}

/* One Listing 7.1 step on a texel's state for encoding e: sample value l at
 * direction d (basis values bd), extra numerator terms extra[i] (the light
 * sample's moment estimate over the sampled area, or 0), weight w. */
inline void lux_progressive_step(__global float4* st, const LuxEncoding* e, const float* bd,
                                 float3 l, const float3* extra, float w, float acceleration) {
  float4 head = st[0];
  head.x += w;
  const float scale = w / head.x;
  float3 delta = l;
  for (int i = 0; i < e->count; ++i) delta -= st[1 + i].xyz * bd[i];
  const float dy = lux_luminance(delta);
  head.y += (dy * dy - head.y) * scale;
  /* Eq. 7.15: blend from the naive denominator 1 to the running mean of B_i^2. */
  const float blend = fmin(1.0f / head.x, 1.0f);
  for (int i = 0; i < e->count; ++i) {
    float4 lobe = st[1 + i];
    const float bi = bd[i];
    lobe.w += (bi * bi - lobe.w) * scale;
    const float integral = blend + (1.0f - blend) * lobe.w;
    const float k = acceleration * scale / integral; /* Eq. 7.14: alpha / k / I_i */
    const float3 previous = lobe.xyz;
    lobe.xyz += (delta * bi + extra[i]) * k;
    if (e->solver == LUX_SOLVER_PROGRESSIVE_NN) lobe.xyz = fmax(lobe.xyz, (float3)(0.0f));
    delta -= (lobe.xyz - previous) * bi; /* Gauss-Seidel (§7.3.1) */
    st[1 + i] = lobe;
  }
  st[0] = head;
}

/* Adds one path's radiance sample to every encoding of a texel. `state`
 * points at the texel's record; l = radiance along the first direction;
 * nee_scale scales the light sample (visibility, firefly clamp). */
inline void lux_basis_accumulate(__global float4* state, __global const LuxEncoding* encodings,
                                 uint encoding_count, __global const float4* dirs,
                                 const LuxBasisSample* s, float3 l, float3 nee, float w,
                                 float acceleration) {
  for (uint k = 0; k < encoding_count; ++k) {
    const LuxEncoding e = encodings[k];
    __global float4* st = state + e.state_offset;
    const float3 d = e.tangent_frame ? s->dir_tangent.xyz : s->dir_world.xyz;
    const float3 dl = e.tangent_frame ? s->nee_tangent.xyz : s->nee_world.xyz;
    float bd[LUX_ENC_MAX_LOBES], bl[LUX_ENC_MAX_LOBES];
    lux_basis_eval(&e, dirs, d, bd);
    const int has_nee = nee.x != 0.0f || nee.y != 0.0f || nee.z != 0.0f;
    if (has_nee) lux_basis_eval(&e, dirs, dl, bl);
    if (e.solver == LUX_SOLVER_PROJECTION) {
      float4 head = st[0];
      head.x += w;
      const float scale = w / head.x;
      for (int i = 0; i < e.count; ++i) {
        float3 moment = LUX_BASIS_MEASURE * bd[i] * l;
        if (has_nee) moment += (LUX_BASIS_NEE_SCALE * bl[i]) * nee;
        float4 lobe = st[1 + i];
        lobe.xyz += (moment - lobe.xyz) * scale;
        lobe.w += (bd[i] * bd[i] - lobe.w) * scale;
        st[1 + i] = lobe;
      }
      st[0] = head;
      continue;
    }
    float3 extra[LUX_ENC_MAX_LOBES];
    for (int i = 0; i < e.count; ++i)
      extra[i] = has_nee ? bl[i] * nee * (LUX_BASIS_NEE_SCALE / LUX_BASIS_MEASURE) : (float3)(0.0f);
    lux_progressive_step(st, &e, bd, l, extra, w, acceleration);
    /* Probes sample the whole sphere already. */
    if (!e.hemisphere_fit && !LUX_PROBE_DOMAIN) {
      /* The sphere fit sees a zero-radiance sample in the opposite direction
       * after each real one (§7.3.1, last paragraph). */
      for (int i = 0; i < e.count; ++i) extra[i] = (float3)(0.0f);
      lux_basis_eval(&e, dirs, -d, bd);
      lux_progressive_step(st, &e, bd, (float3)(0.0f), extra, w, acceleration);
    }
  }
}

#endif /* LUXEL_BAKE_BASIS_H */
