/* Stage 1, the texel domain (thesis §3.4): which texel each path slot of
 * the iteration traces. Device only. */
#ifndef LUXEL_BAKE_TEXEL_DOMAIN_H
#define LUXEL_BAKE_TEXEL_DOMAIN_H

#include "sampling/sequence.h"
#include "shared/bake_args.h"

/* Kensler's hash-based permutation of [0, n) (Correlated Multi-Jittered
 * Sampling, 2013, Listing "permute"): a bijection per pattern p, by cycle
 * walking inside the next power of two. */
inline uint lux_permute(uint i, uint n, uint p) {
  uint w = n - 1u;
  w |= w >> 1;
  w |= w >> 2;
  w |= w >> 4;
  w |= w >> 8;
  w |= w >> 16;
  do {
    i ^= p;
    i *= 0xe170893du;
    i ^= p >> 16;
    i ^= (i & w) >> 4;
    i ^= p >> 8;
    i *= 0x0929eb3fu;
    i ^= p >> 23;
    i ^= (i & w) >> 1;
    i *= 1u | p >> 27;
    i *= 0x6935fa69u;
    i ^= (i & w) >> 11;
    i *= 0x74dcb303u;
    i ^= (i & w) >> 2;
    i *= 0x9e501cc3u;
    i ^= (i & w) >> 2;
    i *= 0xc860a3dfu;
    i &= w;
    i ^= i >> 5;
  } while (i >= n);
  return (i + p) % n;
}

/* Path g of the bake (counted over the whole bake, first_path + gid) takes
 * covered slot perm_pass(g mod N) with pass = g / N: every texel with a
 * valid sample has the same probability, the lightmap fills in random order
 * (a preview of the whole map early), and after k passes every texel has
 * exactly k samples. Slots past the iteration's path count get the invalid
 * key, which the radix sort moves to the end. The key is the covered slot
 * (index into `covered`), not the texel: per-texel state is stored per slot,
 * and slots ascend with texels, so the sorted order is the same either way. */
inline void lux_texel_domain(uint gid, LUX_STAGE_PARAMS(texel_domain)) {
  if (gid >= params.capacity) return;
  if (gid >= params.paths) {
    keys[gid] = 0xFFFFFFFFu;
    return;
  }
#if LUX_ADAPTIVE
  /* An adaptive iteration: alloc_keys writes the keys (bake/adaptive.h). */
  if (params.adaptive_pass) return;
#endif
  const ulong g = params.first_path + gid;
  const uint n = params.covered_count;
  const uint pass = (uint)(g / n);
  const uint j = (uint)(g % n);
  const uint pattern = lux_hash_combine(params.bake_seed ^ 0x9e3779b9u, lux_hash_u32(pass));
  keys[gid] = lux_permute(j, n, pattern);
}

#endif /* LUXEL_BAKE_TEXEL_DOMAIN_H */
