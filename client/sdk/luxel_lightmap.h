/* luxel_lightmap.h: reconstruct lighting from Luxel directional lightmaps.
 * Over 500 lines: a self-contained header by design: an engine copies one file.
 *
 * Self-contained single header: copy it into your
 * engine. Compiles as C99, C++ and OpenCL C; it uses only float arithmetic,
 * sqrt and exp, so porting to GLSL/HLSL is a search and replace.
 *
 * Conventions (they match what the Luxel bake writes; see the bake manifest
 * and docs/reconstruction.md):
 *  - Coefficients encode RADIANCE L(w) = sum_i c_i B_i(w).
 *  - *_irradiance returns IRRADIANCE E(n) = integral over the hemisphere about
 *    n of L(w) max(n.w, 0) dw: a constant radiance L gives pi * L. Outgoing
 *    diffuse radiance is albedo * E / pi.
 *  - *_specular returns outgoing specular RADIANCE for single-scattering GGX
 *    (Smith height-correlated G2, Fresnel f0 + (f90 - f0)(1 - v.h)^5):
 *    integral of L(l) f(v, l) max(n.l, 0) dl. Both are approximations; the
 *    measured error is in docs/reconstruction.md.
 *  - alpha is the GGX alpha (= perceptual roughness squared).
 *  - All directions are unit vectors in one frame (world or tangent space),
 *    passed as separate x, y, z floats; v points from the surface to the eye.
 *  - Colour: every function reads ONE channel. Coefficient i is read at
 *    coeffs[i * stride]: for interleaved RGB pass coeffs + channel, stride 3;
 *    for planar data stride 1.
 *  - Lobe directions (SG axes, Ambient Dice vertices) are 3 floats per lobe,
 *    exactly as listed in the bake manifest ("directions"). The two canonical
 *    Ambient Dice vertex sets are provided below as luxel_ad12_directions and
 *    luxel_ad9_directions.
 *
 * References: core thesis (Roughton 2019, "Interactive Generation of
 * Path-Traced Lightmaps") Ch. 8: §8.1 SH, §8.2 SG (Eq. 8.2), §8.3 Ambient Dice
 * (Eq. 8.3/8.4), §8.4.1 diffuse (Eq. 8.14/8.15), §8.4.2 specular (Eq. 8.17,
 * Listings 8.1 and 8.2); Ramamoorthi & Hanrahan 2001 (SH irradiance);
 * Pettineo, "SG Series" 2016 parts 3 (Hill's irradiance fit) and 4 (specular).
 *
 * OpenCL C 1.2 has no generic address space: define LUXEL_PTR (e.g. as
 * __global or __constant) before including this header to match where your
 * coefficient, direction and LUT arrays live. */
#ifndef LUXEL_LIGHTMAP_H
#define LUXEL_LIGHTMAP_H

/* __OPENCL_VERSION__ is the spec's macro; clang's offline OpenCL C mode
 * defines only __OPENCL_C_VERSION__. */
#if defined(__OPENCL_VERSION__) || defined(__OPENCL_C_VERSION__)
#define LUXEL_OPENCL 1
#endif

#ifdef LUXEL_OPENCL
#define LUXEL_SQRT(x) sqrt(x)
#define LUXEL_EXP(x) exp(x)
#define LUXEL_TABLE __constant
#else
#include <math.h>
#define LUXEL_SQRT(x) sqrtf(x)
#define LUXEL_EXP(x) expf(x)
#define LUXEL_TABLE static const
#endif

/* static inline: valid in C99, C++ and OpenCL C, and never emits a symbol. */
#define LUXEL_FN static inline

#ifndef LUXEL_PTR
#define LUXEL_PTR
#endif

#define LUXEL_PI 3.14159265358979323846f

/* ------------------------------------------------------------------ helpers */

LUXEL_FN float luxel_saturate(float x) {
  return x < 0.0f ? 0.0f : (x > 1.0f ? 1.0f : x);
}

LUXEL_FN float luxel_dot(float ax, float ay, float az, float bx, float by, float bz) {
  return ax * bx + ay * by + az * bz;
}

/* ----------------------------------------------- spherical harmonics (§8.1)
 * Real orthonormal SH, index l(l+1)+m: Y00; Y1-1 ~ y, Y10 ~ z, Y11 ~ x;
 * Y2-2 ~ xy, Y2-1 ~ yz, Y20 ~ 3z^2-1, Y21 ~ xz, Y22 ~ x^2-y^2.
 * count is 4 (L1) or 9 (L2). */

LUXEL_FN float luxel_sh_basis(int i, float x, float y, float z) {
  switch (i) {
    case 0:
      return 0.282094792f; /* 1 / (2 sqrt(pi)) */
    case 1:
      return 0.488602512f * y; /* sqrt(3 / (4 pi)) */
    case 2:
      return 0.488602512f * z;
    case 3:
      return 0.488602512f * x;
    case 4:
      return 1.092548431f * x * y; /* sqrt(15 / (4 pi)) */
    case 5:
      return 1.092548431f * y * z;
    case 6:
      return 0.315391565f * (3.0f * z * z - 1.0f); /* sqrt(5 / (16 pi)) */
    case 7:
      return 1.092548431f * x * z;
    default:
      return 0.546274215f * (x * x - y * y); /* sqrt(15 / (16 pi)) */
  }
}

/* Radiance in direction w. */
LUXEL_FN float luxel_sh_radiance(LUXEL_PTR const float* coeffs, int stride, int count, float wx,
                                 float wy, float wz) {
  float l = 0.0f;
  for (int i = 0; i < count; ++i) l += coeffs[i * stride] * luxel_sh_basis(i, wx, wy, wz);
  return l;
}

/* E(n) = sum A_l c_lm Y_lm(n), A = (pi, 2pi/3, pi/4) (Ramamoorthi & Hanrahan
 * 2001): exact for radiance band-limited to the stored bands. */
LUXEL_FN float luxel_sh_irradiance(LUXEL_PTR const float* coeffs, int stride, int count, float nx,
                                   float ny, float nz) {
  float e = LUXEL_PI * coeffs[0] * luxel_sh_basis(0, nx, ny, nz);
  for (int i = 1; i < count; ++i) {
    const float a = i < 4 ? 2.0f * LUXEL_PI / 3.0f : 0.25f * LUXEL_PI;
    e += a * coeffs[i * stride] * luxel_sh_basis(i, nx, ny, nz);
  }
  return e;
}

/* ------------------------------------------ spherical Gaussians (§8.2)
 * B_i(w) = exp(lambda (w.p_i - 1)) (Eq. 8.2, unit amplitude; the coefficient
 * is the amplitude). dirs: 3 floats per lobe; lambda from the manifest. */

LUXEL_FN float luxel_sg_radiance(LUXEL_PTR const float* coeffs, int stride,
                                 LUXEL_PTR const float* dirs, int count, float lambda, float wx,
                                 float wy, float wz) {
  float l = 0.0f;
  for (int i = 0; i < count; ++i) {
    const float c = luxel_dot(dirs[3 * i], dirs[3 * i + 1], dirs[3 * i + 2], wx, wy, wz);
    l += coeffs[i * stride] * LUXEL_EXP(lambda * (c - 1.0f));
  }
  return l;
}

/* Irradiance from one unit-amplitude lobe, mu_dot_n = p.n: Stephen Hill's
 * fit (Pettineo, "SG Series Part 3", SGIrradianceFitted), normalised by
 * 2 pi / lambda. Same operations as the bake's lux_sg_diffuse_irradiance_hill. */
LUXEL_FN float luxel_sg_lobe_irradiance(float mu_dot_n, float lambda) {
  const float c0 = 0.36f;
  const float c1 = 1.0f / (4.0f * c0);
  const float eml = LUXEL_EXP(-lambda);
  const float em2l = eml * eml;
  const float rl = 1.0f / lambda;
  const float scale = 1.0f + 2.0f * em2l - rl;
  const float bias = (eml - em2l) * rl - em2l;
  const float x = LUXEL_SQRT(1.0f - scale);
  const float x0 = c0 * mu_dot_n;
  const float x1 = c1 * x;
  const float n = x0 + x1;
  float y = luxel_saturate(mu_dot_n);
  if ((x0 < 0.0f ? -x0 : x0) <= x1) y = n * n / x;
  return (scale * y + bias) * (2.0f * LUXEL_PI * rl);
}

LUXEL_FN float luxel_sg_irradiance(LUXEL_PTR const float* coeffs, int stride,
                                   LUXEL_PTR const float* dirs, int count, float lambda, float nx,
                                   float ny, float nz) {
  float e = 0.0f;
  for (int i = 0; i < count; ++i) {
    const float c = luxel_dot(dirs[3 * i], dirs[3 * i + 1], dirs[3 * i + 2], nx, ny, nz);
    e += coeffs[i * stride] * luxel_sg_lobe_irradiance(c, lambda);
  }
  return e;
}

/* Integral over the sphere of the product of two SGs (amplitudes a1, a2,
 * sharpness l1, l2, axes p1, p2): exact (Pettineo part 2, SGInnerProduct). */
LUXEL_FN float luxel_sg_inner_product(float a1, float l1, float p1x, float p1y, float p1z, float a2,
                                      float l2, float p2x, float p2y, float p2z) {
  const float ux = l1 * p1x + l2 * p2x, uy = l1 * p1y + l2 * p2y, uz = l1 * p1z + l2 * p2z;
  const float um = LUXEL_SQRT(ux * ux + uy * uy + uz * uz);
  const float expo = LUXEL_EXP(um - l1 - l2) * a1 * a2;
  const float other = 1.0f - LUXEL_EXP(-2.0f * um);
  return 2.0f * LUXEL_PI * expo * other / um;
}

/* Smallest alpha the SG specular accepts: the NDF-as-SG has sharpness
 * 2 / alpha^2, which overflows float exp near 0. */
#define LUXEL_SG_MIN_ALPHA 0.01f

/* GGX specular from SG radiance lobes, the standard approximation of
 * Pettineo "SG Series Part 4" (SpecularTermSGWarp): the GGX NDF as an SG
 * (amplitude 1 / (pi alpha^2), sharpness 2 / alpha^2) about n, warped to the
 * reflection direction (sharpness / (4 n.v)), integrated exactly against each
 * radiance lobe; the separable Smith visibility, Fresnel and n.l are taken at
 * the warped lobe's axis. All lobe-independent terms are computed once. */
LUXEL_FN float luxel_sg_specular(LUXEL_PTR const float* coeffs, int stride,
                                 LUXEL_PTR const float* dirs, int count, float lambda, float nx,
                                 float ny, float nz, float vx, float vy, float vz, float alpha,
                                 float f0, float f90) {
  const float a = alpha > LUXEL_SG_MIN_ALPHA ? alpha : LUXEL_SG_MIN_ALPHA;
  const float m2 = a * a;
  const float ndf_amplitude = 1.0f / (LUXEL_PI * m2);
  const float ndv_raw = luxel_dot(nx, ny, nz, vx, vy, vz);
  const float warp_sharpness = 2.0f / m2 / (4.0f * (ndv_raw > 0.0001f ? ndv_raw : 0.0001f));
  /* Warped axis: reflect(-v, n). */
  const float rx = 2.0f * ndv_raw * nx - vx, ry = 2.0f * ndv_raw * ny - vy,
              rz = 2.0f * ndv_raw * nz - vz;
  float sum = 0.0f;
  for (int i = 0; i < count; ++i)
    sum += coeffs[i * stride] * luxel_sg_inner_product(ndf_amplitude, warp_sharpness, rx, ry, rz,
                                                       1.0f, lambda, dirs[3 * i], dirs[3 * i + 1],
                                                       dirs[3 * i + 2]);
  const float ndl = luxel_saturate(luxel_dot(nx, ny, nz, rx, ry, rz));
  const float ndv = luxel_saturate(ndv_raw);
  /* 1 / (n.x + sqrt(a^2 + (1 - a^2)(n.x)^2)) = G1(x) / (2 n.x) (Pettineo GGX_V1). */
  const float v1l = 1.0f / (ndl + LUXEL_SQRT(m2 + (1.0f - m2) * ndl * ndl));
  const float v1v = 1.0f / (ndv + LUXEL_SQRT(m2 + (1.0f - m2) * ndv * ndv));
  const float hx = rx + vx, hy = ry + vy, hz = rz + vz;
  const float hl = LUXEL_SQRT(hx * hx + hy * hy + hz * hz);
  const float ldh = hl > 0.0f ? luxel_saturate(luxel_dot(rx, ry, rz, hx, hy, hz) / hl) : 0.0f;
  const float w = (1.0f - ldh) * (1.0f - ldh) * (1.0f - ldh) * (1.0f - ldh) * (1.0f - ldh);
  const float fresnel = f0 + (f90 - f0) * w;
  const float out = sum * v1l * v1v * fresnel * ndl;
  return out > 0.0f ? out : 0.0f;
}

/* ----------------------------------- Ambient Dice cosine lobes (§8.3)
 * B_i(s) = 0.7 x^2 / 2 + 0.3 * 5 x^4 / 6 = 0.35 x^2 + 0.25 x^4,
 * x = max(v_i.s, 0) (Eq. 8.3/8.4). */

LUXEL_FN float luxel_ad_lobe(float cos_to_vertex) {
  const float x = cos_to_vertex > 0.0f ? cos_to_vertex : 0.0f;
  const float x2 = x * x;
  return 0.35f * x2 + 0.25f * x2 * x2;
}

#define LUXEL_AD_SPHERE_COUNT 12
#define LUXEL_AD_HEMISPHERE_COUNT 9

/* The regular icosahedron (0, +-1, +-phi) and cyclic permutations,
 * normalised, in the bake's order (bit-identical to
 * server/engine/encode/basis.cpp icosahedron_vertices()). */
LUXEL_TABLE float luxel_ad12_directions[3 * LUXEL_AD_SPHERE_COUNT] = {
    0.0f,          -0.525731087f, -0.850650787f, -0.525731087f, -0.850650787f, 0.0f,
    -0.850650787f, 0.0f,          -0.525731087f, 0.0f,          -0.525731087f, 0.850650787f,
    -0.525731087f, 0.850650787f,  0.0f,          0.850650787f,  0.0f,          -0.525731087f,
    0.0f,          0.525731087f,  -0.850650787f, 0.525731087f,  -0.850650787f, 0.0f,
    -0.850650787f, 0.0f,          0.525731087f,  0.0f,          0.525731087f,  0.850650787f,
    0.525731087f,  0.850650787f,  0.0f,          0.850650787f,  0.0f,          0.525731087f};

/* The nine hemisphere vertices of §8.3.1 (published to 4 digits, then
 * renormalised; bit-identical to ambient_dice_hemisphere_vertices()). Their
 * mean points along +z: use them in tangent space with the normal = +z. */
LUXEL_TABLE float luxel_ad9_directions[3 * LUXEL_AD_HEMISPHERE_COUNT] = {
    0.525694549f, -0.303496838f, 0.794691741f,  -0.525694549f, -0.303496838f, 0.794691741f,
    0.0f,         0.607064009f,  0.794652939f,  0.85067302f,   0.491084427f,  0.187594041f,
    -0.85067302f, 0.491084427f,  0.187594041f,  0.0f,          -0.982243896f, 0.187608391f,
    -0.85067302f, -0.491084427f, -0.187594041f, 0.85067302f,   -0.491084427f, -0.187594041f,
    0.0f,         0.982243896f,  -0.187608391f};

LUXEL_FN float luxel_ad_radiance(LUXEL_PTR const float* coeffs, int stride,
                                 LUXEL_PTR const float* dirs, int count, float wx, float wy,
                                 float wz) {
  float l = 0.0f;
  for (int i = 0; i < count; ++i)
    l += coeffs[i * stride] *
         luxel_ad_lobe(luxel_dot(dirs[3 * i], dirs[3 * i + 1], dirs[3 * i + 2], wx, wy, wz));
  return l;
}

/* E(n) = pi sum_i b_i (0.05981 + 0.12918 c + 0.07056 c^2), c = v_i.n
 * (Eq. 8.14/8.15; the thesis integrates against cos / pi, hence the pi). */
LUXEL_FN float luxel_ad_irradiance(LUXEL_PTR const float* coeffs, int stride,
                                   LUXEL_PTR const float* dirs, int count, float nx, float ny,
                                   float nz) {
  float e = 0.0f;
  for (int i = 0; i < count; ++i) {
    const float c = luxel_dot(dirs[3 * i], dirs[3 * i + 1], dirs[3 * i + 2], nx, ny, nz);
    e += coeffs[i * stride] * (0.05981f + 0.12918f * c + 0.07056f * c * c);
  }
  return LUXEL_PI * e;
}

/* Listing 8.1's fitted single-lobe specular response before the LUT scale:
 * at low roughness the lobe seen in the mirror direction, at high roughness
 * the diffuse fit, with the diffuse fit's argument moved from R.v_i towards
 * N.v_i as alpha grows. Listing 8.1 uses its own rounding of Eq. 8.14
 * (0.06, 0.129, 0.0697); the LUT was generated against exactly this function,
 * so it is kept as published. */
LUXEL_FN float luxel_ad_specular_lobe(float n_dot_lobe, float r_dot_lobe, float alpha) {
  const float s = LUXEL_SQRT(alpha);
  const float focus =
      luxel_saturate(3.0498910522220495f * s - 6.983002509990005f * alpha +
                     7.388270435580356f * s * alpha - 2.662756921813306f * alpha * alpha);
  const float blend =
      luxel_saturate(-0.4005429486854629f * s + 5.626699351644211f * alpha -
                     6.040098716506305f * s * alpha + 1.9006124935607012f * alpha * alpha);
  const float p = r_dot_lobe + (n_dot_lobe - r_dot_lobe) * focus;
  const float diffuse = 0.06f + 0.129f * p + 0.0697f * p * p;
  const float mirror = luxel_ad_lobe(r_dot_lobe);
  return mirror + (diffuse - mirror) * blend;
}

/* Specular radiance from Ambient Dice radiance lobes (§8.4.2): Listing 8.1
 * per lobe, times the split-sum scale of Eq. 8.17, f0 * lut_f0 + f90 * lut_f90,
 * where (lut_f0, lut_f90) is the Listing 8.2 table (luxel_ad_specular_lut.h)
 * at (n.v, alpha): sample it as a texture or with luxel_ad_lut_sample. The fit
 * assumes lobes over the whole sphere (§8.4); with the 9-vertex hemisphere set
 * the missing lobes' clipping is not compensated (as in the thesis). */
LUXEL_FN float luxel_ad_specular(LUXEL_PTR const float* coeffs, int stride,
                                 LUXEL_PTR const float* dirs, int count, float nx, float ny,
                                 float nz, float vx, float vy, float vz, float alpha, float lut_f0,
                                 float lut_f90, float f0, float f90) {
  const float ndv = luxel_dot(nx, ny, nz, vx, vy, vz);
  const float rx = 2.0f * ndv * nx - vx, ry = 2.0f * ndv * ny - vy, rz = 2.0f * ndv * nz - vz;
  float sum = 0.0f;
  for (int i = 0; i < count; ++i) {
    const float dx = dirs[3 * i], dy = dirs[3 * i + 1], dz = dirs[3 * i + 2];
    sum += coeffs[i * stride] * luxel_ad_specular_lobe(luxel_dot(nx, ny, nz, dx, dy, dz),
                                                       luxel_dot(rx, ry, rz, dx, dy, dz), alpha);
  }
  return sum * (f0 * lut_f0 + f90 * lut_f90);
}

/* Bilinear lookup in the Ambient Dice specular LUT, as a GPU would filter an
 * RG float texture of width size_ndotv, height size_alpha with clamp-to-edge:
 * texel (i, j) holds cell centre n.v = (i + 0.5) / size_ndotv,
 * alpha = (j + 0.5) / size_alpha, channels (f0 scale, f90 scale) at
 * lut[2 * (j * size_ndotv + i) + channel]. Returns one channel. */
LUXEL_FN float luxel_ad_lut_sample(LUXEL_PTR const float* lut, int size_ndotv, int size_alpha,
                                   float ndotv, float alpha, int channel) {
  float u = luxel_saturate(ndotv) * (float)size_ndotv - 0.5f;
  float w = luxel_saturate(alpha) * (float)size_alpha - 0.5f;
  u = u < 0.0f ? 0.0f : (u > (float)(size_ndotv - 1) ? (float)(size_ndotv - 1) : u);
  w = w < 0.0f ? 0.0f : (w > (float)(size_alpha - 1) ? (float)(size_alpha - 1) : w);
  const int i0 = (int)u, j0 = (int)w;
  const int i1 = i0 + 1 < size_ndotv ? i0 + 1 : i0;
  const int j1 = j0 + 1 < size_alpha ? j0 + 1 : j0;
  const float fu = u - (float)i0, fw = w - (float)j0;
  const float a = lut[2 * (j0 * size_ndotv + i0) + channel],
              b = lut[2 * (j0 * size_ndotv + i1) + channel];
  const float c = lut[2 * (j1 * size_ndotv + i0) + channel],
              d = lut[2 * (j1 * size_ndotv + i1) + channel];
  return (a + (b - a) * fu) + ((c + (d - c) * fu) - (a + (b - a) * fu)) * fw;
}

/* ------------------------------------------------------------ light probes
 * Irradiance from a baked probe set (probes.bin, documented in the bake's
 * probes.json and server/engine/probes/probe_file.h), DDGI style (Majercik
 * et al. 2019, "Dynamic Diffuse Global Illumination with Ray-Traced
 * Irradiance Fields"): the 8 probes of the grid cell around the point,
 * trilinear weights, a smooth back-face weight, and with use_visibility the
 * Chebyshev test of the point's distance against each probe's distance
 * moments in the point's direction (so light does not leak through walls).
 * Probes flagged inside geometry, and cells adaptive placement left empty,
 * get weight 0; the rest renormalise. Layouts without a grid (user
 * positions) weigh every probe by 1 / d^2 instead of trilinearly.
 * C and C++ only (the parser reads host memory). */
#ifndef LUXEL_OPENCL
#include <stddef.h>
#include <string.h>

#define LUXEL_PROBE_INSIDE 2u

typedef struct LuxelProbeSet {
  unsigned count, sh_count, vis_side, is_grid, window, mode, record_floats;
  int dims[3];
  float origin[3], spacing, sigma[3];
  const int* grid_index; /* dims[0] * dims[1] * dims[2] entries, or NULL */
  const float* records;  /* count * record_floats: see luxel_probe_* below */
} LuxelProbeSet;

/* Parses probes.bin held in memory (4-byte aligned; the set points into it).
 * Returns 0, or -1 for a wrong magic/version/size. */
LUXEL_FN int luxel_probes_parse(const void* data, size_t bytes, LuxelProbeSet* set) {
  const unsigned char* b = (const unsigned char*)data;
  unsigned h[24];
  if (bytes < 96 || memcmp(b, "LUXPROBE", 8) != 0) return -1;
  memcpy(h, b + 8, 88);
  if (h[0] != 1u || h[1] != 96u) return -1;
  set->count = h[2];
  set->sh_count = h[3];
  set->vis_side = h[4];
  set->is_grid = h[5] & 1u;
  memcpy(set->dims, &h[6], 12);
  memcpy(set->origin, &h[9], 12);
  memcpy(&set->spacing, &h[12], 4);
  set->window = h[13];
  memcpy(set->sigma, &h[14], 12);
  set->mode = h[17];
  set->record_floats = h[18] / 4u;
  {
    const size_t cells =
        set->is_grid ? (size_t)set->dims[0] * (size_t)set->dims[1] * (size_t)set->dims[2] : 0;
    const size_t need = 96 + cells * 4 + (size_t)set->count * set->record_floats * 4;
    if (bytes < need ||
        set->record_floats != 10u + 3u * set->sh_count + 2u * set->vis_side * set->vis_side)
      return -1;
    set->grid_index = set->is_grid ? (const int*)(const void*)(b + 96) : (const int*)0;
    set->records = (const float*)(const void*)(b + 96 + cells * 4);
  }
  return 0;
}

LUXEL_FN const float* luxel_probe_record(const LuxelProbeSet* set, unsigned probe) {
  return set->records + (size_t)probe * set->record_floats;
}

/* The probe's irradiance about n (RGB), with the file's SH window. */
LUXEL_FN void luxel_probe_sh_irradiance(const LuxelProbeSet* set, unsigned probe, float nx,
                                        float ny, float nz, float rgb[3]) {
  const float* sh = luxel_probe_record(set, probe) + 10;
  int c, i;
  for (c = 0; c < 3; ++c) {
    float e = 0.0f;
    for (i = 0; i < (int)set->sh_count; ++i) {
      const int l = i == 0 ? 0 : (i < 4 ? 1 : 2);
      const float a = l == 0 ? LUXEL_PI : (l == 1 ? 2.0f * LUXEL_PI / 3.0f : 0.25f * LUXEL_PI);
      e += set->sigma[l] * a * sh[i * 3 + c] * luxel_sh_basis(i, nx, ny, nz);
    }
    rgb[c] = e;
  }
}

/* The octahedral bin (z up) of unit direction d, as the bake's shared/probe.h. */
LUXEL_FN int luxel_probe_vis_bin(float x, float y, float z, int side) {
  const float l1 = fabsf(x) + fabsf(y) + fabsf(z);
  float px = l1 > 0.0f ? x / l1 : 0.0f, py = l1 > 0.0f ? y / l1 : 0.0f;
  int ix, iy;
  if (z < 0.0f) {
    const float qx = (1.0f - fabsf(py)) * (px >= 0.0f ? 1.0f : -1.0f);
    const float qy = (1.0f - fabsf(px)) * (py >= 0.0f ? 1.0f : -1.0f);
    px = qx;
    py = qy;
  }
  ix = (int)((px * 0.5f + 0.5f) * (float)side);
  iy = (int)((py * 0.5f + 0.5f) * (float)side);
  ix = ix < 0 ? 0 : (ix > side - 1 ? side - 1 : ix);
  iy = iy < 0 ? 0 : (iy > side - 1 ? side - 1 : iy);
  return iy * side + ix;
}

/* DDGI's weight of one probe for shading point p with normal n (trilinear
 * or distance weight `base` applied by the caller). */
LUXEL_FN float luxel_probe_weight(const LuxelProbeSet* set, unsigned probe, float px, float py,
                                  float pz, float nx, float ny, float nz, float bias,
                                  int use_visibility) {
  const float* r = luxel_probe_record(set, probe);
  unsigned flags;
  float dx, dy, dz, d, w, wb;
  memcpy(&flags, &r[3], 4);
  if (flags & LUXEL_PROBE_INSIDE) return 0.0f;
  dx = r[0] - px;
  dy = r[1] - py;
  dz = r[2] - pz;
  d = LUXEL_SQRT(dx * dx + dy * dy + dz * dz);
  /* Smooth back-face term: probes behind the surface count less. */
  wb = d > 0.0f ? (luxel_dot(dx, dy, dz, nx, ny, nz) / d + 1.0f) * 0.5f : 1.0f;
  w = wb * wb + 0.2f;
  if (use_visibility) {
    /* From the probe to the point, lifted off the surface by `bias`. */
    const float qx = px + nx * bias - r[0], qy = py + ny * bias - r[1], qz = pz + nz * bias - r[2];
    const float dq = LUXEL_SQRT(qx * qx + qy * qy + qz * qz);
    if (dq > 0.0f) {
      const int side = (int)set->vis_side;
      const float* vis = r + 10 + 3 * set->sh_count;
      const int bin = luxel_probe_vis_bin(qx / dq, qy / dq, qz / dq, side);
      const float mean = vis[bin * 2], mean2 = vis[bin * 2 + 1];
      if (dq > mean) {
        const float var = fabsf(mean2 - mean * mean);
        const float t = dq - mean;
        float cheb = var / (var + t * t);
        cheb = cheb * cheb * cheb;
        w *= cheb;
      }
    }
    w = w > 1e-6f ? w : 1e-6f;
    /* DDGI's crush of weights under 0.2 (a light cut). */
    if (w < 0.2f) w *= w * w / (0.2f * 0.2f);
  }
  return w;
}

/* Irradiance (RGB, W/m^2) at point p with unit normal n. Returns the sum of
 * weights (0: no usable probe; rgb is then 0). */
LUXEL_FN float luxel_probes_irradiance(const LuxelProbeSet* set, float px, float py, float pz,
                                       float nx, float ny, float nz, int use_visibility,
                                       float rgb[3]) {
  float sum = 0.0f, e[3];
  unsigned k;
  rgb[0] = rgb[1] = rgb[2] = 0.0f;
  if (set->is_grid) {
    const float p[3] = {px, py, pz};
    int base[3], a;
    float f[3];
    for (a = 0; a < 3; ++a) {
      float u = (p[a] - set->origin[a]) / set->spacing;
      int i;
      const int hi = set->dims[a] > 1 ? set->dims[a] - 2 : 0;
      i = (int)floorf(u);
      i = i < 0 ? 0 : (i > hi ? hi : i);
      u -= (float)i;
      f[a] = set->dims[a] > 1 ? (u < 0.0f ? 0.0f : (u > 1.0f ? 1.0f : u)) : 0.0f;
      base[a] = i;
    }
    for (k = 0; k < 8; ++k) {
      const int c[3] = {base[0] + (int)(k & 1u), base[1] + (int)((k >> 1) & 1u),
                        base[2] + (int)((k >> 2) & 1u)};
      float tri = 1.0f, w;
      int probe;
      if (c[0] >= set->dims[0] || c[1] >= set->dims[1] || c[2] >= set->dims[2]) continue;
      for (a = 0; a < 3; ++a) tri *= (k >> a) & 1u ? f[a] : 1.0f - f[a];
      probe = set->grid_index[c[0] + set->dims[0] * (c[1] + set->dims[1] * c[2])];
      if (probe < 0 || tri <= 0.0f) continue;
      w = tri * luxel_probe_weight(set, (unsigned)probe, px, py, pz, nx, ny, nz,
                                   0.1f * set->spacing, use_visibility);
      if (w <= 0.0f) continue;
      luxel_probe_sh_irradiance(set, (unsigned)probe, nx, ny, nz, e);
      rgb[0] += w * e[0];
      rgb[1] += w * e[1];
      rgb[2] += w * e[2];
      sum += w;
    }
  } else {
    for (k = 0; k < set->count; ++k) {
      const float* r = luxel_probe_record(set, k);
      const float dx = r[0] - px, dy = r[1] - py, dz = r[2] - pz;
      const float d2 = dx * dx + dy * dy + dz * dz + 1e-8f;
      const float w = luxel_probe_weight(set, k, px, py, pz, nx, ny, nz, 0.0f, use_visibility) / d2;
      if (w <= 0.0f) continue;
      luxel_probe_sh_irradiance(set, k, nx, ny, nz, e);
      rgb[0] += w * e[0];
      rgb[1] += w * e[1];
      rgb[2] += w * e[2];
      sum += w;
    }
  }
  if (sum > 0.0f) {
    rgb[0] /= sum;
    rgb[1] /= sum;
    rgb[2] /= sum;
  }
  return sum;
}
#endif /* !LUXEL_OPENCL */

#endif /* LUXEL_LIGHTMAP_H */
