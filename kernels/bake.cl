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
 *   LUX_ADAPTIVE         adaptive sampling: iterations after the warm-up
 *                        allocate paths by per-texel error (bake/adaptive.h);
 *                        without it the alloc_* kernels are empty
 *   LUX_DIRECT_ANALYTIC  irradiance lightmaps with lights of closed-form
 *                        irradiance: exact unshadowed direct light at the
 *                        texel point, sampled visibility (bake/raygen.h)
 *   LUX_BASIS            directional encodings (SH, SG, Ambient Dice): the
 *                        first segment is sampled uniformly over the
 *                        hemisphere and each path leaves a LuxBasisSample
 *                        for the accumulator (bake/basis.h)
 *
 * Each kernel is a thin entry point over its stage in kernels/bake/ (one
 * header per stage); its parameters come from the buffer groups of
 * kernels/shared/bake_args.h, which the host binds by name. */

#include "bake/accumulate.h"
#include "bake/adaptive.h"
#include "bake/raygen.h"
#include "bake/resolve.h"
#include "bake/shade.h"
#include "bake/stats.h"
#include "bake/texel_domain.h"

__kernel void texel_domain(LUX_STAGE_PARAMS(texel_domain)) {
  lux_texel_domain((uint)get_global_id(0), LUX_STAGE_ARGS(texel_domain));
}

__kernel void raygen(LUX_STAGE_PARAMS(raygen)) {
  lux_raygen((uint)get_global_id(0), LUX_STAGE_ARGS(raygen));
}

__kernel void shade(LUX_STAGE_PARAMS(shade)) {
  lux_shade((uint)get_global_id(0), LUX_STAGE_ARGS(shade));
}

__kernel void resolve_shadows(LUX_STAGE_PARAMS(resolve_shadows)) {
  lux_resolve_shadows((uint)get_global_id(0), LUX_STAGE_ARGS(resolve_shadows));
}

__kernel void resolve_texel_shadows(LUX_STAGE_PARAMS(resolve_texel_shadows)) {
  lux_resolve_texel_shadows((uint)get_global_id(0), LUX_STAGE_ARGS(resolve_texel_shadows));
}

__kernel void accumulate(LUX_STAGE_PARAMS(accumulate)) {
  lux_accumulate((uint)get_global_id(0), LUX_STAGE_ARGS(accumulate));
}

/* Launched with work-groups of LUX_STATS_GROUP items. */
__kernel void accum_stats(LUX_STAGE_PARAMS(accum_stats)) {
  __local float l_err[LUX_STATS_GROUP];
  __local float l_lum[LUX_STATS_GROUP];
  __local uint l_min[LUX_STATS_GROUP];
  __local float2 l_ref[LUX_STATS_GROUP];
  lux_accum_stats((uint)get_global_id(0), (uint)get_local_id(0), (uint)get_local_size(0),
                  (uint)get_group_id(0), l_err, l_lum, l_min, l_ref, LUX_STAGE_ARGS(accum_stats));
}

/* Adaptive sampling (bake/adaptive.h); empty without LUX_ADAPTIVE. Launched
 * with work-groups of LUX_ALLOC_GROUP items, alloc_scan as one group. */
__kernel void alloc_weights(LUX_STAGE_PARAMS(alloc_weights)) {
#if LUX_ADAPTIVE
  __local uint l_q[LUX_ALLOC_GROUP];
  lux_alloc_weights((uint)get_global_id(0), (uint)get_local_id(0), (uint)get_group_id(0), l_q,
                    LUX_STAGE_ARGS(alloc_weights));
#endif
}

__kernel void alloc_scan(LUX_STAGE_PARAMS(alloc_scan)) {
#if LUX_ADAPTIVE
  __local ulong l_s[LUX_ALLOC_GROUP];
  lux_alloc_scan((uint)get_local_id(0), l_s, LUX_STAGE_ARGS(alloc_scan));
#endif
}

__kernel void alloc_keys(LUX_STAGE_PARAMS(alloc_keys)) {
#if LUX_ADAPTIVE
  __local uint l_q[LUX_ALLOC_GROUP];
  lux_alloc_keys((uint)get_global_id(0), (uint)get_local_id(0), (uint)get_group_id(0), l_q,
                 LUX_STAGE_ARGS(alloc_keys));
#endif
}
