/* Stage 4, shadow-ray results: the any-hit queries of the active list's
 * shadow rays decide which NEE contributions count. Device only. */
#ifndef LUXEL_BAKE_RESOLVE_H
#define LUXEL_BAKE_RESOLVE_H

#include "bake/path.h"
#include "shared/bake_args.h"

/* Adds each unoccluded light sample to its path's radiance. */
inline void lux_resolve_shadows(uint j, LUX_STAGE_PARAMS(resolve_shadows)) {
  if (j >= (uint)*count) return;
  const uint slot = active[j] & LUX_SLOT_MASK;
  if (occluded[slot]) return;
  const float4 c = shadow_contrib[slot];
  if (c.x == 0.0f && c.y == 0.0f && c.z == 0.0f) return;
#if LUX_RADIANCE_CACHE
  /* c.w = 1: a light sample the radiance cache leaves out, the texel
   * point's (raygen.h) or a path's last bounce's (shade.h). */
  paths[slot].radiance.xyz += c.xyz;
  if (c.w > 0.0f) paths[slot].uncached.xyz += c.xyz;
#else
  paths[slot].radiance += c;
#endif
}

/* The texel point's shadow rays with directional encodings: visibility goes
 * to the basis sample (the accumulator needs the light sample apart from the
 * radiance along the first segment). */
inline void lux_resolve_texel_shadows(uint j, LUX_STAGE_PARAMS(resolve_texel_shadows)) {
  if (j >= (uint)*count) return;
  const uint slot = active[j] & LUX_SLOT_MASK;
  basis_samples[slot].nee.w = occluded[slot] ? 0.0f : 1.0f;
}

#endif /* LUXEL_BAKE_RESOLVE_H */
