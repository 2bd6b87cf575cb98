/* The arguments of the bake kernels, declared once for host and device.
 *
 * Buffers come in groups (what they hold, who sizes them). A group is an
 * X-macro list of entries X(kind, type, name, what):
 *   kind  buffer  a __global array of `type` owned by the bake (BakeBuffers)
 *         value   a struct passed by value (`type` is a shared struct)
 *         live    the active-path list of one launch (which of the two
 *                 ping-pong lists and counts is current changes per bounce)
 *   what  the buffer's name in allocation errors and memory reports.
 *
 * A kernel's parameter list is `LuxBakeParams params` followed by the groups
 * it names, each marked `in` (const) or `out`. bake.cl declares its kernels
 * and the stage functions of kernels/bake/ from these lists
 * (LUX_STAGE_PARAMS); the host binds arguments from the same lists by name
 * (server/engine/bake/bake_kernels.cpp), so a host buffer that is
 * missing, renamed or of the wrong value type is a compile error, and the
 * order of arguments cannot drift between the two sides.
 *
 * Buffers a feature does not need are bound to 16-byte placeholders: the
 * signatures stay fixed while the code paths compile out. */
#ifndef LUXEL_SHARED_BAKE_ARGS_H
#define LUXEL_SHARED_BAKE_ARGS_H

#include "shared/bake.h"
#include "shared/geometry.h"
#include "shared/light.h"
#include "shared/texture.h"

/* ---- Groups ------------------------------------------------------------- */

/* Scene: sized by the scene and the atlas, uploaded once. */
#define LUX_GROUP_scene(X)                                           \
  X(buffer, LuxSurfaceTri, tris, "surface triangles")                \
  X(buffer, LuxMaterial, materials, "materials")                     \
  X(buffer, LuxTriangleUV, atlas_uvs, "atlas uvs")                   \
  X(buffer, uint, instance_first, "instance table")                  \
  X(buffer, uint, covered, "covered texels")                         \
  X(buffer, uint, sample_offsets, "sample-info offsets") /* §4.2 */ \
  X(buffer, uint, sample_words, "sample-info words")                 \
  X(buffer, float4, probes, "probe positions") /* probe domain */

/* Lights (§6.1): the light table with its selection alias table, and the sky. */
#define LUX_GROUP_lights(X)                                 \
  X(buffer, LuxLight, lights, "lights")                     \
  X(buffer, LuxAliasEntry, light_select, "light selection") \
  X(value, LuxSky, sky, "sky")                              \
  X(buffer, float, sky_texels, "sky texels")                \
  X(buffer, float, sky_block_cdfs, "sky block cdfs")        \
  X(buffer, float, sky_texel_cdfs, "sky texel cdfs")

/* Material textures (kernels/shared/texture.h), the per-triangle
 * material UV set 1, present only when a material reads TEXCOORD_1, and the
 * per-triangle tangents, present only when a material has a normal map. */
#define LUX_GROUP_textures(X)                            \
  X(buffer, LuxTexture, textures, "textures")            \
  X(buffer, uint, texels, "texture texels")              \
  X(buffer, LuxTriangleUV, material_uv1, "material uv1") \
  X(buffer, LuxTriangleTangents, tangents, "normal-map tangents")

/* Path state: sized by the batch (paths per iteration). keys = the texel of
 * each path slot, sorted; offsets = the offset buffer (Listing 3.1). */
#define LUX_GROUP_paths(X)                                  \
  X(buffer, uint, keys, "path texel keys")                  \
  X(buffer, uint, offsets, "offset buffer")                 \
  X(buffer, LuxPath, paths, "paths")                        \
  X(buffer, LuxRay, rays, "rays")                           \
  X(buffer, LuxHit, hits, "hits")                           \
  X(buffer, LuxRay, shadow_rays, "shadow rays")             \
  X(buffer, float4, shadow_contrib, "shadow contributions") \
  X(buffer, int, occluded, "occlusion flags")               \
  X(buffer, uint, alive, "alive flags")                     \
  X(buffer, uint, tagged, "tagged slots")

/* The active list of a launch: slot ids (with the octant tag of §5.4 in the
 * top bits) and the live count, which stays on the device. */
#define LUX_GROUP_live(X)               \
  X(live, uint, active, "active paths") \
  X(live, int, count, "live count")

/* Accumulation: sized by the lightmap (weighted Welford per texel, §3.2.2),
 * the statistics partials, the benchmark-mode reference, the radiance
 * cache's means and the first-bounce guide's histograms (placeholders
 * without LUX_RADIANCE_CACHE and LUX_GUIDING). */
#define LUX_GROUP_accum(X)                                                        \
  X(buffer, float4, mean, "accumulated mean")                                     \
  X(buffer, float4, m2, "accumulated M2")                                         \
  X(buffer, float2, weight, "accumulated weight")                                 \
  X(buffer, uint, spp, "samples per texel")                                       \
  X(buffer, uint, nonfinite, "non-finite counter")                                \
  X(buffer, LuxAccumStats, stats, "stats partials")                               \
  X(buffer, float4, reference, "reference lightmap")                              \
  X(buffer, float4, radiance_cache, "radiance cache") /* bake/radiance_cache.h */ \
  X(buffer, float4, guide, "first-bounce guide")      /* bake/guiding.h */

/* Adaptive sampling (kernels/bake/adaptive.h), sized by the lightmap:
 * each covered slot's integer allocation weight, and per block of
 * LUX_ALLOC_GROUP slots the weights' sum, scanned in place into the
 * blocks' first CDF value (entry `blocks` = the total). 16-byte
 * placeholders without LUX_ADAPTIVE. */
#define LUX_GROUP_alloc(X)                           \
  X(buffer, uint, alloc_weights, "adaptive weights") \
  X(buffer, ulong, alloc_blocks, "adaptive block sums")

/* Directional encodings (Ch. 7-8): one sample record per path slot, the
 * encoding table, lobe directions and the per-texel solver state. */
#define LUX_GROUP_encodings(X)                              \
  X(buffer, LuxBasisSample, basis_samples, "basis samples") \
  X(buffer, LuxEncoding, encodings, "encodings")            \
  X(buffer, float4, basis_dirs, "basis directions")         \
  X(buffer, float4, basis_state, "basis state")

/* ---- Kernels: the groups each one takes, in order ------------------------ */

#define LUX_KERNEL_texel_domain(G) G(in, scene) G(out, paths)
#define LUX_KERNEL_raygen(G) \
  G(in, scene)               \
  G(in, textures) G(in, lights) G(in, accum) G(out, paths) G(out, live) G(out, encodings)
#define LUX_KERNEL_shade(G) \
  G(in, scene) G(in, textures) G(in, lights) G(in, accum) G(out, paths) G(in, live)
#define LUX_KERNEL_resolve_shadows(G) G(out, paths) G(in, live)
#define LUX_KERNEL_resolve_texel_shadows(G) G(in, paths) G(in, live) G(out, encodings)
#define LUX_KERNEL_accumulate(G) G(in, scene) G(in, paths) G(out, accum) G(out, encodings)
#define LUX_KERNEL_accum_stats(G) G(in, scene) G(out, accum)
#define LUX_KERNEL_alloc_weights(G) G(in, scene) G(in, accum) G(out, alloc)
#define LUX_KERNEL_alloc_scan(G) G(out, alloc)
#define LUX_KERNEL_alloc_keys(G) G(out, paths) G(in, alloc)

/* Every bake kernel, for the host's kernel table. */
#define LUX_BAKE_KERNELS(K) \
  K(texel_domain)           \
  K(raygen)                 \
  K(shade)                  \
  K(resolve_shadows)        \
  K(resolve_texel_shadows) K(accumulate) K(accum_stats) K(alloc_weights) K(alloc_scan) K(alloc_keys)

/* Work-group size of accum_stats (its local reduction arrays). */
#define LUX_STATS_GROUP 256
/* Work-group size of alloc_weights and alloc_keys (one block of the CDF). */
#define LUX_ALLOC_GROUP 256

/* ---- Device declarations ------------------------------------------------- */
#ifdef LUX_DEVICE

#define LUX_DECL_in_buffer(T, name) __global const T* name
#define LUX_DECL_out_buffer(T, name) __global T* name
#define LUX_DECL_in_live(T, name) __global const T* name
#define LUX_DECL_out_live(T, name) __global T* name
#define LUX_DECL_in_value(T, name) T name
#define LUX_DECL_out_value(T, name) T name
#define LUX_DECL_in(kind, T, name, what) , LUX_DECL_in_##kind(T, name)
#define LUX_DECL_out(kind, T, name, what) , LUX_DECL_out_##kind(T, name)
#define LUX_DECL_GROUP(access, group) LUX_GROUP_##group(LUX_DECL_##access)
#define LUX_FORWARD(kind, T, name, what) , name
#define LUX_FORWARD_GROUP(access, group) LUX_GROUP_##group(LUX_FORWARD)

/* The parameter list of kernel `k` (and of its stage function), and the
 * argument list that forwards it. */
#define LUX_STAGE_PARAMS(k) LuxBakeParams params LUX_KERNEL_##k(LUX_DECL_GROUP)
#define LUX_STAGE_ARGS(k) params LUX_KERNEL_##k(LUX_FORWARD_GROUP)
/* One group's parameters / arguments, for helpers shared by stages. */
#define LUX_GROUP_PARAMS(access, group) LUX_DECL_GROUP(access, group)
#define LUX_GROUP_ARGS(group) LUX_FORWARD_GROUP(in, group)

#endif /* LUX_DEVICE */

#endif /* LUXEL_SHARED_BAKE_ARGS_H */
