/* The wavefront lightmap path tracer (thesis Ch. 3-6). One program holds
 * every bake stage except ray traversal (kernels/intersect.cl) and the data-
 * parallel primitives (radix_sort.cl, compact.cl, offset_buffer.cl).
 *
 * Features (-D from the bake's FeatureSet; absent = compiled out):
 *   LUX_LIGHT_POINT / _SPOT / _DIRECTIONAL / _EMISSIVE, LUX_SKY, LUX_SKY_IMAGE
 *                        light types present (kernels/shading/lights.h)
 *   LUX_NEE              any light at all: next-event estimation
 *   LUX_TEXTURES         material textures (base colour, metallic-roughness)
 *   LUX_EMISSIVE_TEXTURE an emissive material has a texture
 *   LUX_SPECULAR         some material needs the GGX layer
 *   LUX_SORT_DIRECTIONS  extension rays are tagged with their octant (§5.4)
 *   LUX_COMPACTION       live paths are compacted between bounces (§5.1);
 *                        without it every slot runs and dead ones return
 *   LUX_FILTER_GAUSSIAN  1.5-texel Gaussian accumulation filter (§3.2.2)
 *   LUX_SEQUENCE_RANDOM  independent random numbers instead of Sobol (ablation)
 *   LUX_BASIS            directional encodings (SH, SG, Ambient Dice): the
 *                        first segment is sampled uniformly over the
 *                        hemisphere and each path leaves a LuxBasisSample
 *                        for the accumulator (bake/basis.h)
 *
 * Buffers a feature does not need are bound to a 16-byte placeholder, so the
 * kernel signatures stay fixed while the code paths compile out. */

#include "shared/bake.h"
#include "shared/geometry.h"
#include "shared/light.h"
#include "shared/ray_offset.h"
#include "shared/sample_info.h"
#include "shared/texture.h"
#include "sampling/sequence.h"
#include "sampling/warp.h"
#include "shading/bsdf.h"
#include "shading/distribution.h"
#include "shading/lights.h"
#include "shading/texture.h"
#include "primitives/offset_buffer.h"
#include "bake/surface.h"
#include "bake/scatter.h"
#if LUX_BASIS
#include "bake/basis.h"
#endif

#define LUX_TAG_SHIFT 29u
#define LUX_SLOT_MASK 0x1FFFFFFFu

#define LUX_LIGHT_PARAMS                                                                  \
  __global const LuxLight *lights, __global const float *light_cdf, LuxSky sky,           \
      __global const float *sky_texels, __global const float *sky_marginal,               \
      __global const float *sky_conditional
#define LUX_TEXTURE_PARAMS __global const LuxTexture *textures, __global const uint *texels

/* The texel point is a "sensor" with f = 1. Irradiance keeps cosine-weighted
 * first segments (weight pi); directional encodings need radiance samples
 * uniform over the hemisphere (§3.4, "Accumulation into Linear Bases"), so
 * there the path carries radiance (weight 1) and the accumulator applies
 * 2 pi cos for irradiance. Russian roulette is relative to that weight. */
#if LUX_BASIS
#define LUX_SENSOR_PDF(cos_theta) lux_uniform_hemisphere_pdf()
#define LUX_SENSOR_WEIGHT 1.0f
#else
#define LUX_SENSOR_PDF(cos_theta) lux_cosine_hemisphere_pdf(cos_theta)
#define LUX_SENSOR_WEIGHT M_PI_F
#endif

/* Kensler's hash-based permutation of [0, n) (Correlated Multi-Jittered
 * Sampling, 2013, Listing "permute"): a bijection per pattern p, by cycle
 * walking inside the next power of two. */
inline uint lux_permute(uint i, uint n, uint p) {
  uint w = n - 1u;
  w |= w >> 1; w |= w >> 2; w |= w >> 4; w |= w >> 8; w |= w >> 16;
  do {
    i ^= p; i *= 0xe170893du; i ^= p >> 16; i ^= (i & w) >> 4; i ^= p >> 8;
    i *= 0x0929eb3fu; i ^= p >> 23; i ^= (i & w) >> 1; i *= 1u | p >> 27;
    i *= 0x6935fa69u; i ^= (i & w) >> 11; i *= 0x74dcb303u; i ^= (i & w) >> 2;
    i *= 0x9e501cc3u; i ^= (i & w) >> 2; i *= 0xc860a3dfu; i &= w; i ^= i >> 5;
  } while (i >= n);
  return (i + p) % n;
}

/* An independent (hash-based) uniform number for Russian roulette. The
 * padded Owen-scrambled Sobol dimensions of successive vertices are not
 * independent enough for a decision that compounds over the path: with them
 * the furnace box (albedo 0.9, 40 bounces) came out 1.7 % dark
 * (closed_form_test FurnaceBoxAtExtremeScalesAndHighAlbedo); with this, it
 * agrees. Roulette gains nothing from stratification anyway. */
inline float lux_independent_1d(uint index, uint dimension, uint seed) {
  const uint h = lux_hash_u32(lux_hash_combine(lux_hash_combine(seed, index), dimension));
  return (float)(h >> 8) * 0x1p-24f;
}

inline uint lux_texel_seed(uint texel, uint bake_seed) {
  return lux_hash_combine(lux_hash_u32(texel), bake_seed);
}

/* ---- 1. Texel domain (§3.4) --------------------------------------------------
 * Path g of the bake (counted over the whole bake, first_path + gid) takes
 * texel covered[perm_pass(g mod N)] with pass = g / N: every texel with a
 * valid sample has the same probability, the lightmap fills in random order
 * (a preview of the whole map early), and after k passes every texel has
 * exactly k samples. Slots past the iteration's path count get the invalid
 * key, which the radix sort moves to the end. */
__kernel void texel_domain(LuxBakeParams params, __global const uint* covered, ulong first_path,
                           __global uint* keys, uint capacity) {
  const uint gid = (uint)get_global_id(0);
  if (gid >= capacity) return;
  if (gid >= params.paths) {
    keys[gid] = 0xFFFFFFFFu;
    return;
  }
  const ulong g = first_path + gid;
  const uint n = params.covered_count;
  const uint pass = (uint)(g / n);
  const uint j = (uint)(g % n);
  const uint pattern = lux_hash_combine(params.bake_seed ^ 0x9e3779b9u, lux_hash_u32(pass));
  keys[gid] = covered[lux_permute(j, n, pattern)];
}

/* ---- Shared vertex logic --------------------------------------------------------- */

/* Next-event estimation from surface s. `sensor`: vertex 0 (f = 1, cosine
 * pdf). Otherwise the material's BSDF in the local frame (t, b, n), wo local.
 * Writes the shadow ray and its unoccluded contribution (throughput applied). */
inline void lux_next_event(LUX_LIGHT_PARAMS, LUX_TEXTURE_PARAMS,
                           __global const LuxSurfaceTri* tris,
                           __global const LuxMaterial* materials, LuxBakeParams params,
                           const LuxSurface* s, int sensor, const LuxBsdf* bsdf, float3 t,
                           float3 b, float3 n, float3 wo_local, float3 throughput, uint index,
                           uint dim, uint seed, LuxRay* shadow_ray, float3* contribution) {
  *shadow_ray = lux_no_ray();
  *contribution = (float3)(0.0f);
#if LUX_NEE
  const float u_sel = lux_sample_1d(index, dim + LUX_DIM_LIGHT_SELECT, seed);
  const float2 u_pt = lux_sample_2d(index, dim + LUX_DIM_LIGHT_POINT, seed);
  LuxLightSample ls;
  if (!lux_sample_light(lights, light_cdf, params.light_count, sky, sky_texels, sky_marginal,
                        sky_conditional, s->p, u_sel, u_pt, &ls))
    return;
  if (!(ls.pdf > 0.0f) || dot(ls.wi, s->ng) <= 0.0f) return;
  float3 radiance = ls.radiance;
#if LUX_EMISSIVE_TEXTURE
  if (ls.triangle >= 0) {
    const LuxSurface e = lux_surface_at(tris, ls.triangle, ls.bary.x, ls.bary.y);
    const LuxMaterial em = materials[e.material];
    if (em.emissive_tex >= 0)
      radiance *= lux_texture_sample(texels, textures[em.emissive_tex], e.uv).xyz;
  }
#endif
  const float3 wi_local = lux_to_local(ls.wi, t, b, n);
  const float cos_i = wi_local.z;
  if (cos_i <= 0.0f) return;
  /* MIS only for lights a BSDF ray can also reach (emissive triangles, the
   * sky); the sun disc and punctual lights are NEE-only with weight 1. */
  const int mis = !ls.is_delta && ls.mis;
  float3 f_weighted;
  if (sensor) {
    const float w = mis ? lux_power_heuristic(ls.pdf, LUX_SENSOR_PDF(cos_i)) : 1.0f;
    f_weighted = (float3)(w);
  } else {
    f_weighted = (float3)(0.0f);
    for (int layer = 0; layer < 2; ++layer) {
      const float3 f = lux_bsdf_eval_layer(bsdf, layer, wo_local, wi_local);
      if (lux_max3(f) <= 0.0f) continue;
      const float w =
          mis ? lux_power_heuristic(ls.pdf, lux_bsdf_pdf_layer(bsdf, layer, wo_local, wi_local))
              : 1.0f;
      f_weighted += f * w;
    }
  }
  *contribution = throughput * f_weighted * radiance * (cos_i / ls.pdf);
  const float3 org = lux_offset_origin(s->p, s->ng, ls.wi, params.offset_scale);
  if (!isfinite(ls.dist)) {
    *shadow_ray = lux_make_ray(org, ls.wi, INFINITY);
    return;
  }
  /* Finite lights: aim at the light point pulled back off its own surface by
   * the same robust offset (kernels/shared/ray_offset.h), so the shadow ray
   * neither reaches the emitter itself nor depends on the scene's scale (a
   * relative tmax margin fails at 1e-3 units, where the origin offset is
   * larger than the margin). Direction unnormalised, tmax = 1. */
  const float3 q = lux_offset_origin(s->p + ls.wi * ls.dist, -ls.wi, -ls.wi, params.offset_scale);
  const float3 d = q - org;
  /* Receiver and light point closer than the offsets (touching surfaces):
   * nothing can lie between them. */
  *shadow_ray = dot(d, ls.wi) > 0.0f ? lux_make_ray(org, d, 1.0f) : lux_no_ray();
#endif
}

/* ---- 2. Primary rays from texels (§3.4, Listing 4.2) ------------------------ */
__kernel void raygen(LuxBakeParams params, __global const uint* sorted_texels,
                     __global const uint* offsets, __global const int* path_count,
                     __global const uint* sample_offsets, __global const uint* sample_words,
                     __global const LuxTriangleUV* atlas_uvs, __global const uint* instance_first,
                     __global const LuxSurfaceTri* tris, __global const LuxMaterial* materials,
                     LUX_TEXTURE_PARAMS, LUX_LIGHT_PARAMS, __global const uint* texel_spp,
                     __global LuxPath* paths, __global LuxRay* rays, __global LuxRay* shadow_rays,
                     __global float4* shadow_contrib, __global uint* active,
                     __global LuxBasisSample* basis_samples) {
  const uint gid = (uint)get_global_id(0);
  if (gid >= (uint)*path_count) return;
  const uint texel = sorted_texels[gid];
  /* Rank of this path among the texel's paths of this iteration: the
   * texel's sample index continues its progressive sequence (§6.2) without
   * atomics, so results do not depend on scheduling. */
  uint first = 0, end = 0;
  lux_offset_range(offsets, texel, params.texel_count, &first, &end);
  const uint index = texel_spp[texel] + (gid - first);
  const uint seed = lux_texel_seed(texel, params.bake_seed);

  /* Listing 4.2: choose one of the texel's valid Hammersley positions. */
  const uint word_offset = sample_offsets[texel];
  const uint valid = popcount(sample_words[word_offset]) + popcount(sample_words[word_offset + 1]);
  const float u_sample = lux_sample_1d(index, LUX_DIM_TEXEL_SAMPLE, seed);
  const uint rank = min((uint)(u_sample * (float)valid), valid - 1u);
  uint instance, mesh_tri, hammersley;
  lux_sample_info_lookup(sample_words, word_offset, rank, &instance, &mesh_tri, &hammersley);
  const int tri = (int)(instance_first[instance] + mesh_tri);
  const uint tx = texel % params.width, ty = texel / params.width;
  const float2 offset = lux_hammersley64(hammersley);
  const LuxTriangleUV uvt = atlas_uvs[tri];
  /* Barycentrics in the lightmap, in the sample point's frame so the
   * arithmetic stays in small magnitudes (§3.4: "high-precision
   * calculations ... to avoid invalid values"; kernels/shared/sample_info.h). */
  float w0, w1, w2;
  lux_texel_barycentrics((float2)(uvt.uv0.x, uvt.uv0.y), (float2)(uvt.uv1.x, uvt.uv1.y),
                         (float2)(uvt.uv2.x, uvt.uv2.y), (float)params.width,
                         (float)params.height, tx, ty, offset, &w0, &w1, &w2);
  const float2 bary = (float2)(w1, w2);
  const LuxSurface s = lux_surface_at(tris, tri, bary.x, bary.y);

  LuxPath path;
  path.texel = texel;
  path.sample_index = index;
  path.seed = seed;
  path.depth = 0;
  path.sample_pos = (float2)((float)tx + offset.x, (float)ty + offset.y);
  path.pad = (uint)tri;
  path.radiance = (float4)(0.0f);
  path.prev_pos = (float4)(s.p, 0.0f);

  float3 t, b;
  lux_onb(s.ns, &t, &b);
  const uint dim = LUX_DIM_VERTEX(0);
  LuxRay shadow;
  float3 contribution;
  LuxBsdf unused_bsdf;
  lux_next_event(lights, light_cdf, sky, sky_texels, sky_marginal, sky_conditional, textures,
                 texels, tris, materials, params, &s, 1, &unused_bsdf, t, b, s.ns,
                 (float3)(0.0f, 0.0f, 1.0f), (float3)(1.0f), index, dim, seed, &shadow,
                 &contribution);
  shadow_rays[gid] = shadow;
  shadow_contrib[gid] = (float4)(contribution, 0.0f);

  /* First segment about the shading normal: cosine-weighted (weight pi) for
   * irradiance, uniform (weight 1, radiance) for directional encodings. A
   * direction under the geometric surface (smoothed normals) carries nothing. */
  const float2 u_dir = lux_sample_2d(index, dim + LUX_DIM_DIRECTION, seed);
#if LUX_BASIS
  /* The texel's tangent frame, reproducible by an engine: x follows the
   * lightmap's +u on the surface, z the shading normal. */
  const float3 tn = lux_lightmap_tangent(tris[tri], uvt, s.ns, t);
  t = tn;
  b = cross(s.ns, tn);
  const float3 dir_local = lux_uniform_hemisphere(u_dir);
#else
  const float3 dir_local = lux_cosine_hemisphere(u_dir);
#endif
  const float3 wi = lux_to_world(dir_local, t, b, s.ns);
  const int ok = dot(wi, s.ng) > 0.0f;
  path.throughput = (float4)(LUX_SENSOR_WEIGHT, LUX_SENSOR_WEIGHT, LUX_SENSOR_WEIGHT,
                             LUX_SENSOR_PDF(dir_local.z));
#if LUX_BASIS
  {
    LuxBasisSample bs;
    bs.dir_world = (float4)(wi, dir_local.z);
    bs.dir_tangent = (float4)(dir_local, dir_local.z);
    /* The light sample as radiance over density: the irradiance contribution
     * without its cosine. Visibility (nee.w) comes from resolve_texel_shadows. */
    const float3 ld = shadow.dir_tmax.xyz;
    const float len = length(ld);
    const float3 lw = len > 0.0f ? ld / len : (float3)(0.0f, 0.0f, 1.0f);
    const float3 ll = lux_to_local(lw, t, b, s.ns);
    const float cos_l = dot(lw, s.ns);
    bs.nee_world = (float4)(lw, cos_l);
    bs.nee_tangent = (float4)(ll, cos_l);
    bs.nee = cos_l > 0.0f && len > 0.0f ? (float4)(contribution / cos_l, 0.0f) : (float4)(0.0f);
    basis_samples[gid] = bs;
  }
#endif
  path.alive = ok ? 1u : 0u;
  paths[gid] = path;
  rays[gid] = ok ? lux_make_ray(lux_offset_origin(s.p, s.ng, wi, params.offset_scale), wi, INFINITY) : lux_no_ray();
#if LUX_SORT_DIRECTIONS
  const uint octant = (wi.x < 0.0f ? 1u : 0u) | (wi.y < 0.0f ? 2u : 0u) | (wi.z < 0.0f ? 4u : 0u);
  active[gid] = gid | (octant << LUX_TAG_SHIFT);
#else
  active[gid] = gid;
#endif
}

/* ---- 3. Shading of closest hits (§5.1 step 3b/3d) ---------------------------
 * One work-item per live path (active list). Adds emission (MIS-weighted
 * against the NEE that the previous vertex did), then at vertices within the
 * bounce limit: NEE, BSDF sampling of the extension ray (Eq. 6.2), Russian
 * roulette. Writes alive[j] for compaction. */
__kernel void shade(LuxBakeParams params, __global const uint* active, __global const int* count,
                    __global const LuxHit* hits, __global const LuxRay* rays_in,
                    __global const LuxSurfaceTri* tris, __global const LuxMaterial* materials,
                    LUX_TEXTURE_PARAMS, LUX_LIGHT_PARAMS, __global LuxPath* paths,
                    __global LuxRay* rays, __global LuxRay* shadow_rays,
                    __global float4* shadow_contrib, __global uint* alive_flags,
                    __global uint* tagged) {
  const uint j = (uint)get_global_id(0);
  if (j >= (uint)*count) return;
  const uint slot = active[j] & LUX_SLOT_MASK;
  LuxPath path = paths[slot];
  alive_flags[j] = 0u;
  tagged[j] = slot;
  shadow_rays[slot] = lux_no_ray();
  shadow_contrib[slot] = (float4)(0.0f);
  if (!path.alive) return;

  const LuxRay ray = rays_in[slot];
  const LuxHit hit = hits[slot];
  const float3 dir = ray.dir_tmax.xyz;
  float3 throughput = path.throughput.xyz;
  const float prev_pdf = path.throughput.w;

  if (hit.prim < 0) {
#if LUX_SKY || LUX_SKY_IMAGE
    const float3 l = lux_sky_radiance(sky, sky_texels, dir);
    float w = 1.0f;
    if (prev_pdf > 0.0f && params.sky_light >= 0)
      w = lux_power_heuristic(prev_pdf, lux_sky_pdf(sky, light_cdf, params.sky_light,
                                                    sky_marginal, sky_conditional, dir));
    path.radiance.xyz += throughput * l * w;
#endif
    path.alive = 0u;
    paths[slot] = path;
    rays[slot] = lux_no_ray();
    return;
  }

  const LuxSurface s = lux_surface_at(tris, hit.prim, hit.u, hit.v);
  const LuxMaterial m = materials[s.material];
  const float3 wo = -normalize(dir);

#if LUX_LIGHT_EMISSIVE
  if ((m.flags & LUX_MATERIAL_EMISSIVE) &&
      (dot(wo, s.ng_winding) > 0.0f || (m.flags & LUX_MATERIAL_DOUBLE_SIDED))) {
    float3 le = m.emission.xyz;
#if LUX_EMISSIVE_TEXTURE
    if (m.emissive_tex >= 0) le *= lux_texture_sample(texels, textures[m.emissive_tex], s.uv).xyz;
#endif
    float w = 1.0f;
    if (prev_pdf > 0.0f && s.light >= 0)
      w = lux_power_heuristic(prev_pdf, lux_light_pdf_triangle(lights, light_cdf, s.light,
                                                               path.prev_pos.xyz, s.p,
                                                               s.ng_winding));
    path.radiance.xyz += throughput * le * w;
  }
#endif

  path.depth += 1u;
  if (path.depth > params.max_bounces) {
    path.alive = 0u;
    paths[slot] = path;
    rays[slot] = lux_no_ray();
    return;
  }

  /* Material at the hit. Shading frame on the side the ray arrives from. */
  float3 base = m.base_color.xyz;
  float metallic = m.metallic, roughness = m.roughness;
#if LUX_TEXTURES
  if (m.base_color_tex >= 0) base *= lux_texture_sample(texels, textures[m.base_color_tex], s.uv).xyz;
  if (m.metallic_roughness_tex >= 0) {
    const float4 mr = lux_texture_sample(texels, textures[m.metallic_roughness_tex], s.uv);
    roughness *= mr.y;
    metallic *= mr.z;
  }
#endif
  const LuxBsdf bsdf = lux_make_bsdf(base, metallic, roughness);
  LuxSurface sf = s;
  if (dot(wo, sf.ng) < 0.0f) {
    sf.ng = -sf.ng;
    sf.ns = -sf.ns;
  }
  float3 t, b;
  lux_onb(sf.ns, &t, &b);
  float3 wo_local = lux_to_local(wo, t, b, sf.ns);
  /* Shading normal facing away from the viewer (bent normals): clamp so the
   * BSDF stays defined. */
  if (wo_local.z <= 1e-4f) wo_local = normalize((float3)(wo_local.x, wo_local.y, 1e-4f));

  const uint dim = LUX_DIM_VERTEX(path.depth);
  LuxRay shadow;
  float3 contribution;
  lux_next_event(lights, light_cdf, sky, sky_texels, sky_marginal, sky_conditional, textures,
                 texels, tris, materials, params, &sf, 0, &bsdf, t, b, sf.ns, wo_local,
                 throughput, path.sample_index, dim, path.seed, &shadow, &contribution);
  shadow_rays[slot] = shadow;
  shadow_contrib[slot] = (float4)(contribution, 0.0f);

  /* Extension ray (Eq. 6.2: one layer chosen stochastically). */
  const float u_layer = lux_sample_1d(path.sample_index, dim + LUX_DIM_LAYER, path.seed);
  const float2 u_dir = lux_sample_2d(path.sample_index, dim + LUX_DIM_DIRECTION, path.seed);
  float3 wi_local, weight;
  float pdf;
  const int layer = lux_bsdf_sample(&bsdf, wo_local, u_layer, u_dir, &wi_local, &weight, &pdf);
  const float3 wi = lux_to_world(wi_local, t, b, sf.ns);
  int ok = layer >= 0 && pdf > 0.0f && dot(wi, sf.ng) > 0.0f && lux_finite3(weight);
  throughput *= weight;
  /* Russian roulette (§5.1) on the throughput relative to the sensor's pi. */
  if (ok && path.depth >= params.rr_depth) {
    const float q = fmin(0.95f, lux_max3(throughput) / LUX_SENSOR_WEIGHT);
    const float u_rr = lux_independent_1d(path.sample_index, dim + LUX_DIM_ROULETTE, path.seed);
    if (u_rr >= q) ok = 0;
    else throughput /= q;
  }
  path.throughput = (float4)(throughput, pdf);
  path.prev_pos = (float4)(sf.p, 0.0f);
  path.alive = ok ? 1u : 0u;
  paths[slot] = path;
  rays[slot] = ok ? lux_make_ray(lux_offset_origin(sf.p, sf.ng, wi, params.offset_scale), wi, INFINITY) : lux_no_ray();
  alive_flags[j] = path.alive;
#if LUX_SORT_DIRECTIONS
  const uint octant = (wi.x < 0.0f ? 1u : 0u) | (wi.y < 0.0f ? 2u : 0u) | (wi.z < 0.0f ? 4u : 0u);
  tagged[j] = slot | (octant << LUX_TAG_SHIFT);
#endif
}

/* ---- 4. Shadow-ray results ---------------------------------------------------- */
__kernel void resolve_shadows(__global const uint* active, __global const int* count,
                              __global const int* occluded, __global const float4* shadow_contrib,
                              __global LuxPath* paths) {
  const uint j = (uint)get_global_id(0);
  if (j >= (uint)*count) return;
  const uint slot = active[j] & LUX_SLOT_MASK;
  if (occluded[slot]) return;
  const float4 c = shadow_contrib[slot];
  if (c.x == 0.0f && c.y == 0.0f && c.z == 0.0f) return;
  paths[slot].radiance += c;
}

/* The texel point's shadow rays in basis mode: visibility goes to the basis
 * sample (the accumulator needs the light sample apart from the radiance
 * along the first segment). */
__kernel void resolve_texel_shadows(__global const uint* active, __global const int* count,
                                    __global const int* occluded,
                                    __global LuxBasisSample* basis_samples) {
  const uint j = (uint)get_global_id(0);
  if (j >= (uint)*count) return;
  const uint slot = active[j] & LUX_SLOT_MASK;
  basis_samples[slot].nee.w = occluded[slot] ? 0.0f : 1.0f;
}

/* ---- 5. Gather accumulation (§3.2.2, Listing 3.2) -----------------------------
 * One work-item per covered texel: exclusive access, so the running mean and
 * variance use Welford's algorithm (weighted form, West 1979) without atomics.
 * mean.w / m2.w track luminance, whose variance gives the error estimate.
 * weight = (sum w, sum w^2); spp counts the texel's own paths (box sense),
 * which also advances its sample sequence. A non-finite sample is dropped and
 * counted, never accumulated. */
inline float lux_filter_weight(float2 d) {
#if LUX_FILTER_GAUSSIAN
  /* PBRT's truncated Gaussian, radius 1.5 texels, alpha 2, separable. */
  const float r = 1.5f, alpha = 2.0f;
  const float edge = exp(-alpha * r * r);
  const float wx = fmax(0.0f, exp(-alpha * d.x * d.x) - edge);
  const float wy = fmax(0.0f, exp(-alpha * d.y * d.y) - edge);
  return wx * wy;
#else
  return 1.0f;
#endif
}

inline void lux_welford(float4 x, float w, float4* mean, float4* m2, float2* weight) {
  const float w_new = (*weight).x + w;
  const float4 delta = x - *mean;
  *mean += delta * (w / w_new);
  *m2 += w * delta * (x - *mean);
  *weight = (float2)(w_new, (*weight).y + w * w);
}

/* One path's sample for the accumulator: its irradiance estimate and, in
 * basis mode, the radiance along its first segment (l) and the texel point's
 * light sample (nee, visibility applied). 0 when non-finite (dropped). The
 * firefly clamp scales all three alike. */
inline int lux_path_sample(__global const LuxPath* paths,
                           __global const LuxBasisSample* basis_samples, uint p,
                           float clamp_luminance, float3* irradiance, float3* l, float3* nee) {
  *l = paths[p].radiance.xyz;
#if LUX_BASIS
  const LuxBasisSample bs = basis_samples[p];
  *nee = bs.nee.xyz * bs.nee.w;
  *irradiance = *l * (LUX_TWO_PI_F * bs.dir_world.w) + *nee * fmax(bs.nee_world.w, 0.0f);
  if (!lux_finite3(*irradiance) || !lux_finite3(*nee)) return 0;
#else
  *nee = (float3)(0.0f);
  *irradiance = *l;
  if (!lux_finite3(*irradiance)) return 0;
#endif
  if (clamp_luminance > 0.0f) {
    const float y = lux_luminance(*irradiance);
    if (y > clamp_luminance) {
      const float f = clamp_luminance / y;
      *irradiance *= f;
      *l *= f;
      *nee *= f;
    }
  }
  return 1;
}

#if LUX_BASIS
#define LUX_BASIS_ADD(p, w)                                                                    \
  do {                                                                                         \
    const LuxBasisSample bs_ = basis_samples[p];                                               \
    lux_basis_accumulate(basis_state + (size_t)texel * basis_stride, encodings, encoding_count, \
                         basis_dirs, &bs_, l, nee, (w), acceleration);                         \
  } while (0)
#else
#define LUX_BASIS_ADD(p, w)
#endif

__kernel void accumulate(LuxBakeParams params, __global const uint* covered,
                         __global const uint* offsets, __global const LuxPath* paths,
                         __global const LuxSurfaceTri* tris, __global float4* mean_buf,
                         __global float4* m2_buf, __global float2* weight_buf,
                         __global uint* texel_spp, __global uint* nonfinite,
                         __global const LuxBasisSample* basis_samples,
                         __global const LuxEncoding* encodings, uint encoding_count,
                         uint basis_stride, __global const float4* basis_dirs,
                         __global float4* basis_state, float acceleration) {
  const uint c = (uint)get_global_id(0);
  if (c >= params.covered_count) return;
  const uint texel = covered[c];
  uint first = 0, end = 0;
  const int own = lux_offset_range(offsets, texel, params.texel_count, &first, &end);
#if !LUX_FILTER_GAUSSIAN
  if (!own) return;
#endif
  float4 mean = mean_buf[texel], m2 = m2_buf[texel];
  float2 weight = weight_buf[texel];
  uint dropped = 0;
  const int tx = (int)(texel % params.width), ty = (int)(texel / params.width);
#if LUX_FILTER_GAUSSIAN
  /* Neighbours' paths within the radius, but only from the same instance
   * and a similarly oriented surface: a filter must not carry light across
   * a chart seam into a different surface. */
  const float2 centre = (float2)((float)tx + 0.5f, (float)ty + 0.5f);
  float3 my_normal = (float3)(0.0f);
  int my_instance = -1;
  if (own) {
    const LuxSurfaceTri st = tris[paths[first].pad];
    my_instance = as_int(st.p2.w);
    my_normal = normalize(cross(st.p1.xyz - st.p0.xyz, st.p2.xyz - st.p0.xyz));
  }
  int touched = 0;
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      const int nx = tx + dx, ny = ty + dy;
      if (nx < 0 || ny < 0 || nx >= (int)params.width || ny >= (int)params.height) continue;
      uint nf, ne;
      if (!lux_offset_range(offsets, (uint)(ny * (int)params.width + nx), params.texel_count, &nf, &ne))
        continue;
      for (uint p = nf; p < ne; ++p) {
        const LuxPath path = paths[p];
        if (dx != 0 || dy != 0) {
          if (my_instance < 0) continue; /* no own path to compare against this time */
          const LuxSurfaceTri st = tris[path.pad];
          if (as_int(st.p2.w) != my_instance) continue;
          const float3 nn = normalize(cross(st.p1.xyz - st.p0.xyz, st.p2.xyz - st.p0.xyz));
          if (dot(nn, my_normal) < 0.9f) continue;
        }
        const float w = lux_filter_weight(path.sample_pos - centre);
        if (!(w > 0.0f)) continue;
        float3 e, l, nee;
        if (!lux_path_sample(paths, basis_samples, p, params.clamp_luminance, &e, &l, &nee)) {
          ++dropped;
          continue;
        }
        lux_welford((float4)(e, lux_luminance(e)), w, &mean, &m2, &weight);
        LUX_BASIS_ADD(p, w);
        touched = 1;
      }
    }
  }
  if (!touched && !own) return;
#else
  for (uint p = first; p < end; ++p) {
    float3 e, l, nee;
    if (!lux_path_sample(paths, basis_samples, p, params.clamp_luminance, &e, &l, &nee)) {
      ++dropped;
      continue;
    }
    lux_welford((float4)(e, lux_luminance(e)), 1.0f, &mean, &m2, &weight);
    LUX_BASIS_ADD(p, 1.0f);
  }
#endif
  mean_buf[texel] = mean;
  m2_buf[texel] = m2;
  weight_buf[texel] = weight;
  texel_spp[texel] += own ? end - first : 0u;
  if (dropped) atomic_add(nonfinite, dropped);
}

/* ---- 6. Progress statistics -----------------------------------------------------
 * Per work-group partial sums of the relative standard error of each covered
 * texel's mean (DESIGN.md "Accuracy and error reporting") and the minimum
 * samples per texel; the host adds the few partials. Relative std. error =
 * sqrt(var / n_eff) / mean with var = m2 / W and n_eff = W^2 / sum w^2. A
 * texel with fewer than 2 samples counts as 100 % error; a black texel with
 * zero variance as 0. */
__kernel void accum_stats(LuxBakeParams params, __global const uint* covered,
                          __global const float4* mean_buf, __global const float4* m2_buf,
                          __global const float2* weight_buf, __global const uint* texel_spp,
                          __global LuxAccumStats* partials, __local float* l_err,
                          __local uint* l_min, __global const float4* reference,
                          uint has_reference, __local float2* l_ref) {
  const uint gid = (uint)get_global_id(0), lid = (uint)get_local_id(0);
  const uint lsize = (uint)get_local_size(0);
  float err = 0.0f;
  float2 ref_err = (float2)(0.0f);
  uint spp = 0xFFFFFFFFu;
  if (gid < params.covered_count) {
    const uint texel = covered[gid];
    if (has_reference) {
      const float3 d = mean_buf[texel].xyz - reference[texel].xyz;
      const float3 r = reference[texel].xyz;
      const float3 d2 = d * d;
      ref_err = (float2)((d2.x + d2.y + d2.z) / 3.0f,
                         (d2.x / (r.x * r.x + 1e-2f) + d2.y / (r.y * r.y + 1e-2f) +
                          d2.z / (r.z * r.z + 1e-2f)) / 3.0f);
    }
    spp = texel_spp[texel];
    const float2 w = weight_buf[texel];
    if (spp < 2u || !(w.x > 0.0f)) {
      err = 1.0f;
    } else {
      const float var = fmax(0.0f, m2_buf[texel].w / w.x);
      const float n_eff = w.x * w.x / fmax(w.y, 1e-30f);
      const float y = mean_buf[texel].w;
      const float se = sqrt(var / n_eff);
      err = se <= 0.0f ? 0.0f : (y > 0.0f ? fmin(se / y, 1.0f) : 1.0f);
    }
  }
  l_err[lid] = err;
  l_min[lid] = spp;
  l_ref[lid] = ref_err;
  barrier(CLK_LOCAL_MEM_FENCE);
  for (uint stride = lsize / 2; stride > 0; stride >>= 1) {
    if (lid < stride) {
      l_err[lid] += l_err[lid + stride];
      l_min[lid] = min(l_min[lid], l_min[lid + stride]);
      l_ref[lid] += l_ref[lid + stride];
    }
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  if (lid == 0) {
    LuxAccumStats s;
    s.rel_error_sum = l_err[0];
    s.error_texels = 0;
    s.min_spp = l_min[0];
    s.pad = 0;
    s.reference = (float4)(l_ref[0], 0.0f, 0.0f);
    partials[get_group_id(0)] = s;
  }
}
