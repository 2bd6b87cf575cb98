/* Structs of the wavefront bake pipeline, shared by host and device.
 *
 * One bake iteration (thesis §3.2.2 + §5.1):
 *   texel domain -> radix sort by texel -> offset buffer (Listing 3.1)
 *   -> raygen (Listing 4.2; vertex 0 = the texel's surface point)
 *   -> [closest hit -> shade (emission, NEE, extension, RR) -> any hit for
 *       the shadow rays -> resolve shadows -> compaction] x bounces
 *   -> gather accumulation per texel (Listing 3.2, Welford).
 * All paths of one iteration live in slot order = sorted texel order, so the
 * accumulation kernel finds a texel's paths through the offset buffer. */
#ifndef LUXEL_SHARED_BAKE_H
#define LUXEL_SHARED_BAKE_H

#include "shared/compat.h"
#include "shared/texture.h"

#ifndef LUX_DEVICE
namespace luxel::cl {
#endif

/* Surface data of one world triangle (TriangleSoup order), 128 bytes.
 *   p0.w (int) material index;  p1.w (int) emissive light index or -1;
 *   p2.w (int) instance index. n*: world-space shading normals (w unused).
 *   uv*: material UVs (TEXCOORD_0).
 *   front: +1, or -1 for a triangle of a mirroring instance, whose front face
 *   is the clockwise one (glTF 2.0 §3.7.4; front_face_sign in
 *   server/engine/common/math.h): front * cross(p1 - p0, p2 - p0) is the
 *   front normal. Vertices stay in the file's order, so barycentrics, UVs
 *   and the sample-info records need no remapping. */
typedef struct LuxSurfaceTri {
  float4 p0;
  float4 p1;
  float4 p2;
  float4 n0;
  float4 n1;
  float4 n2;
  float2 uv0;
  float2 uv1;
  float2 uv2;
  float front;
  float pad;
} LuxSurfaceTri;

/* Per-vertex tangents of one world triangle (TriangleSoup order), 48 bytes,
 * present only when a used material has a normal map (LUX_NORMAL_MAP):
 * xyz = world-space tangent (+u of the normal texture's UV set), w = the
 * bitangent sign in world space (bitangent = cross(n, t) * w, glTF 2.0
 * §3.7.2.1; the file's sign times the sign of the instance transform's
 * determinant, since a mirroring transform flips handedness). Triangles
 * without a normal map hold zeros. */
typedef struct LuxTriangleTangents {
  float4 t0;
  float4 t1;
  float4 t2;
} LuxTriangleTangents;

/* Device material, 208 bytes. A slot's texture is -1 when absent.
 *   flags bit 0: double-sided; bit 1: emits light.
 *   specular: rgb = F0 of the dielectric layer, w = its F90. Without
 *     KHR_materials_specular, rgb = ((ior - 1) / (ior + 1))^2
 *     (KHR_materials_ior; 0.04 at the glTF default ior 1.5) and w = 1; with
 *     it, rgb = min(F0(ior) * specularColorFactor, 1) * specularFactor and
 *     w = specularFactor (the extension's dielectric_f0 / dielectric_f90). */
typedef struct LuxMaterial {
  float4 base_color; /* linear rgb, a = alpha factor */
  float4 emission;   /* rgb = emissiveFactor * strength (radiance), w unused */
  float4 specular;   /* rgb = dielectric F0, w = dielectric F90 */
  float metallic;
  float roughness;
  int flags;
  float alpha_cutoff;
  LuxTextureSlot base_color_tex;
  LuxTextureSlot metallic_roughness_tex;
  LuxTextureSlot emissive_tex;
  LuxTextureSlot normal_tex; /* tangent-space normal map (LUX_NORMAL_MAP) */
  float normal_scale;        /* normalTextureInfo.scale: multiplies the map's x and y */
  float pad[3];
} LuxMaterial;

#define LUX_MATERIAL_DOUBLE_SIDED 1
#define LUX_MATERIAL_EMISSIVE 2

/* State of one path, 112 bytes.
 *   throughput.w:  solid-angle pdf of the last BSDF sample (0 = no MIS, e.g.
 *                  the first segment from a texel when no light can be hit)
 *   prev_pos.w:    with first-bounce guiding (kernels/bake/guiding.h): the
 *                  guide bin of the first direction (-1: none, the
 *                  direction was under the surface); 0 otherwise
 *   prev_normal:   the normal the previous vertex sampled its light about
 *                  (MIS of an escaping ray against the sky's pdf); w: with
 *                  guiding, the luminance of the texel point's light sample
 *                  (set at the first hit), which the guide leaves out
 *   uncached:      with the radiance cache (kernels/bake/radiance_cache.h):
 *                  rgb = the part of `radiance` the cache leaves out: the
 *                  light-sampled share of the direct light and the light
 *                  that went max_bounces bounces (lux_cache_left_out; it
 *                  can be negative); w = 1 for a path that feeds the
 *                  cache, 0 for one that may gather. Unused (zero) without
 *                  it. */
typedef struct LuxPath {
  float4 throughput;
  float4 radiance;
  float4 prev_pos;
  float4 prev_normal;
  float4 uncached;
  uint texel;
  uint sample_index; /* index into the texel's progressive sequence (§6.2) */
  uint seed;         /* per-texel decorrelation seed */
  uint depth;        /* scattering vertices so far (0 = the texel point) */
  float2 sample_pos; /* texel-space position of the primary sample */
  uint alive;
  uint pad;
} LuxPath;

/* First-bounce guiding (kernels/bake/guiding.h): a texel's two histograms
 * of LUX_GUIDE_BINS floats are LUX_GUIDE_STRIDE float4 of the accumulation
 * group's guide buffer and of the checkpoint. */
#define LUX_GUIDE_BINS 16
#define LUX_GUIDE_STRIDE 8 /* the frozen histogram, then the current epoch's */

/* Per-bake constants and the iteration's counts, passed by value to every
 * bake kernel (kernels/shared/bake_args.h). 104 bytes, 8-aligned (the ulong
 * first_path; server/engine/bake/layout_check.cpp). */
typedef struct LuxBakeParams {
  uint width;
  uint height;
  uint texel_count;   /* width * height */
  uint covered_count; /* texels with >= 1 valid sample */
  uint bake_seed;
  uint max_bounces; /* indirect bounces after the texel point */
  uint rr_depth;    /* Russian roulette from this depth on */
  uint light_count;
  int sky_light;         /* index of the sky entry in the light table, or -1 */
  float clamp_luminance; /* 0 = off */
  uint paths;            /* paths in this iteration */
  float offset_scale;    /* ray-offset scale: min(1, scene extent) (bake/surface.h) */
  ulong first_path;      /* paths traced before this iteration (texel domain, §3.4) */
  uint capacity;         /* path slots of the batch buffers */
  uint encoding_count;   /* directional encodings (entries of the encodings table) */
  uint basis_stride;     /* float4 of encoding state per texel */
  float acceleration;    /* alpha of Eq. 7.14 (progressive solvers) */
  uint has_reference;    /* 1: the reference buffer holds a lightmap (benchmark mode) */
  /* Adaptive sampling (LUX_ADAPTIVE, kernels/bake/adaptive.h): 1 when this
   * iteration's paths are allocated by per-texel error instead of the
   * uniform texel domain; the luminance under which a texel's relative error
   * counts as absolute (dark floor); weight units per unit of relative error
   * (the map's mean error maps to a fixed weight); the defensive weight every
   * texel gets beside its error, in weight units. */
  uint adaptive_pass;
  float alloc_floor;
  float alloc_scale;
  float alloc_mix;
  float alloc_cap; /* most weight units of a texel's error term */
  /* Distributed bakes (shared/shard.h): this bake traces shard shard_index
   * of shard_count of every texel's sample sequence (count <= 1: all). */
  uint shard_index;
  uint shard_count;
} LuxBakeParams;

/* Per-work-group partial statistics of the accumulation buffer. */
typedef struct LuxAccumStats {
  /* sum over covered texels of coverage x relative std. error (coverage:
   * the share of the texel's 64 sample positions on geometry) */
  float rel_error_sum;
  float luminance_sum; /* sum over covered texels of the mean luminance */
  uint min_spp;
  float coverage_sum; /* sum over covered texels of their coverage */
  /* With a reference lightmap (benchmark mode, DESIGN.md "Accuracy"):
   * x = sum over covered texels of the mean over RGB of (x - ref)^2,
   * y = the same of (x - ref)^2 / (ref^2 + 1e-2) (relMSE); z, w unused. */
  float4 reference;
} LuxAccumStats;

/* ---- Directional encodings (thesis §3.4 "Accumulation into Linear
 * Bases", Ch. 7-8). Compiled in only with LUX_BASIS. */

/* Where the first segment of a path went and what direct light the texel
 * point saw, one per path slot (80 bytes). Directions are given in both
 * encoding frames: world space, and the texel's tangent frame (z = shading
 * normal, x = direction of increasing lightmap u projected onto the tangent
 * plane, y = z cross x). w of the direction fields: cosine to the normal.
 *   nee.xyz: w_mis * L_e / p_light of the texel point's light sample (radiance
 *            over density, i.e. what multiplies B_i(w_l) in the moment
 *            estimate); nee.w: 1 when the shadow ray was unoccluded. */
typedef struct LuxBasisSample {
  float4 dir_world;
  float4 dir_tangent;
  float4 nee_world;
  float4 nee_tangent;
  float4 nee;
} LuxBasisSample;

#define LUX_ENC_SH 0
#define LUX_ENC_SG 1
#define LUX_ENC_AD 2

#define LUX_SOLVER_PROJECTION 0
#define LUX_SOLVER_PROGRESSIVE 1
#define LUX_SOLVER_PROGRESSIVE_NN 2

#define LUX_ENC_MAX_LOBES 12

/* One requested encoding, 32 bytes. A texel's state is `basis_stride` float4:
 * per encoding one header (x = total sample weight, y = running mean of the
 * squared luminance residual, z/w unused) then `count` lobes (rgb = amplitude,
 * w = running mean of B_i^2, the spherical-integral estimate of Eq. 7.15). */
typedef struct LuxEncoding {
  int kind;           /* LUX_ENC_* */
  int count;          /* coefficients (lobes) */
  int first_dir;      /* first lobe direction in the direction table (SG, AD) */
  int state_offset;   /* float4 index of the header within a texel's state */
  int tangent_frame;  /* 1: directions in the texel's tangent frame; 0: world */
  int hemisphere_fit; /* 1: least squares over the hemisphere (§7.2.1); 0: over
                         the sphere, with a zero-radiance mirrored sample after
                         each real one (end of §7.3.1) */
  int solver;         /* LUX_SOLVER_* */
  float sharpness;    /* SG lambda */
} LuxEncoding;

#ifndef LUX_DEVICE
}  // namespace luxel::cl
#endif

#endif /* LUXEL_SHARED_BAKE_H */
