/* The wavefront lightmap path tracer (thesis Ch. 3-6). One program holds
 * every bake stage except ray traversal (kernels/intersect.cl) and the data-
 * parallel primitives (radix_sort.cl, compact.cl, offset_buffer.cl).
 *
 * Features: -D options from the bake's FeatureSet, absent = compiled out.
 * They are listed, each with what it compiles in, once for host and device
 * in kernels/shared/features.h (LUX_FEATURES); the lights, materials and
 * bake groups there are this program's.
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
#include "shared/features.h"

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
  __local float l_cov[LUX_STATS_GROUP];
  __local uint l_min[LUX_STATS_GROUP];
  __local float2 l_ref[LUX_STATS_GROUP];
  lux_accum_stats((uint)get_global_id(0), (uint)get_local_id(0), (uint)get_local_size(0),
                  (uint)get_group_id(0), l_err, l_lum, l_cov, l_min, l_ref,
                  LUX_STAGE_ARGS(accum_stats));
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
