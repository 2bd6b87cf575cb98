/* Edge-avoiding a-trous wavelet filter over the lightmap's texel domain
 * (Dammertz et al. 2010, "Edge-avoiding A-Trous wavelet transform for fast
 * global illumination filtering"), with the variance-guided luminance weight
 * of SVGF (Schied et al. 2017, §4.3-4.4). One launch per iteration, tap
 * spacing 1, 2, 4, ...; the 5x5 B3-spline kernel h = (1, 4, 6, 4, 1) / 16.
 *
 * Work-item = texel. Uncovered texels pass through and are never read as
 * taps; taps from another chart weigh 0 (charts that touch in the atlas are
 * not neighbours on the surface); the normal and tangent-plane weights stop
 * the filter at geometric creases and steps within a chart; the luminance
 * weight stops it at shadow edges unless the difference is within the
 * noise (sigma_luminance standard errors of the texel mean).
 *
 * The variance of each texel's mean is filtered along with the colour, with
 * the squared weights (SVGF Eq. 6), so later, wider iterations compare
 * luminance against the noise left after the earlier ones. */

#include "shared/denoise.h"

#define LUX_DN_H0 0.375f
#define LUX_DN_H1 0.25f
#define LUX_DN_H2 0.0625f

inline float lux_dn_h(int i) {
  const int a = abs(i);
  return a == 0 ? LUX_DN_H0 : (a == 1 ? LUX_DN_H1 : LUX_DN_H2);
}

/* max(0, c)^e; native functions: the weights need no full precision (they
 * stay deterministic on one device). */
inline float lux_dn_power(float c, float e) {
  return c > 0.0f ? native_exp2(e * native_log2(c)) : 0.0f;
}

inline float lux_dn_luminance(float4 c) {
  return dot(c.xyz, (float3)(0.2126f, 0.7152f, 0.0722f));
}

/* 3x3 Gaussian of the variance within the texel's chart (SVGF §4.4: the
 * raw per-texel variance is itself noisy). */
inline float lux_dn_variance_3x3(const LuxDenoiseParams p, int x, int y, uint chart,
                                 __global const float* variance, __global const float4* position,
                                 __global const uint* charts) {
  float sum = 0.0f, wsum = 0.0f;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const int qx = x + dx, qy = y + dy;
      if (qx < 0 || qy < 0 || qx >= p.width || qy >= p.height) continue;
      const int q = qy * p.width + qx;
      if (position[q].w <= 0.0f || charts[q] != chart) continue;
      const float w = (dx == 0 ? 0.5f : 0.25f) * (dy == 0 ? 0.5f : 0.25f);
      sum += w * variance[q];
      wsum += w;
    }
  return sum / wsum; /* the centre tap is always there */
}

__kernel void denoise_atrous(const LuxDenoiseParams p, __global const float4* color_in,
                             __global const float* variance_in, __global float4* color_out,
                             __global float* variance_out, __global const float4* position,
                             __global const float4* normal, __global const uint* charts) {
  const int gid = (int)get_global_id(0);
  if (gid >= p.width * p.height) return;
  const float4 c = color_in[gid];
  const float4 pos = position[gid];
  if (pos.w <= 0.0f) {
    color_out[gid] = c;
    variance_out[gid] = variance_in[gid];
    return;
  }
  const int x = gid % p.width, y = gid / p.width;
  const uint chart = charts[gid];
  const float3 n = normal[gid].xyz;
  const float lum = lux_dn_luminance(c);
  const float var_p = max(lux_dn_variance_3x3(p, x, y, chart, variance_in, position, charts), 0.0f);
  const float eps = 1e-6f * fabs(lum) + 1e-20f;
  const float plane_scale = 1.0f / (p.sigma_plane * pos.w);
  float3 sum = (float3)(0.0f);
  float wsum = 0.0f, vsum = 0.0f;
  for (int dy = -2; dy <= 2; ++dy) {
    const int qy = y + dy * p.step;
    if (qy < 0 || qy >= p.height) continue;
    for (int dx = -2; dx <= 2; ++dx) {
      const int qx = x + dx * p.step;
      if (qx < 0 || qx >= p.width) continue;
      const int q = qy * p.width + qx;
      const float4 qpos = position[q];
      if (qpos.w <= 0.0f || charts[q] != chart) continue;
      const float4 qc = color_in[q];
      const float plane = dot(n, qpos.xyz - pos.xyz) * plane_scale;
      const float w_normal = lux_dn_power(dot(n, normal[q].xyz), p.sigma_normal);
      /* Symmetric in p and q: both texels' noise (a bright outlier's own
       * variance estimate is high, so a weight by the centre's alone would
       * pull bright texels down and keep dim ones, biasing the mean low). */
      const float sd = native_sqrt(var_p + max(variance_in[q], 0.0f));
      const float w_lum = fabs(lux_dn_luminance(qc) - lum) / (p.sigma_luminance * sd + eps);
      const float w = lux_dn_h(dx) * lux_dn_h(dy) * w_normal * native_exp(-plane * plane - w_lum);
      sum += w * qc.xyz;
      wsum += w;
      vsum += w * w * variance_in[q];
    }
  }
  /* wsum > 0: the centre tap has weight h0^2. */
  color_out[gid] = (float4)(sum / wsum, c.w);
  variance_out[gid] = vsum / (wsum * wsum);
}
