/* Progressive low-discrepancy sample sequences (thesis §6.2).
 *
 * Every quantity a path samples (lightmap hemisphere direction, light choice,
 * BSDF layer, BSDF direction, ...) is a *dimension*; a texel draws sample
 * `index` of its own sequence for each dimension. Neighbouring texels must not
 * share sequences (§6.2, after O'Donnell), so each texel owns a random 32-bit
 * `seed` and every sequence is randomised by it.
 *
 * The sequence is Owen-scrambled Sobol after Burley, "Practical Hash-based
 * Owen Scrambling" (JCGT 9(4), 2020):
 *   - the sample index is itself Owen-scrambled ("shuffled") per seed and
 *     dimension, so the first 2^k samples of every texel are an aligned block
 *     of 2^k Sobol points, i.e. a (0,k,2)-net in base 2, for every k;
 *   - Sobol dimensions 0 and 1 (a (0,2)-sequence) give the point;
 *   - each coordinate gets a nested uniform (Owen) scramble, implemented as a
 *     Laine-Karras style hash on the bit-reversed value. The hash constants are
 *     Vegdahl's improved ones ("Building a Better LK Hash", 2021), which
 *     remove the visible structure of Burley's original constants.
 * Owen scrambling keeps the net property and makes every single point
 * uniformly distributed over seeds, so estimates stay unbiased.
 *
 * 1D and 2D requests are separate namespaces: lux_sample_1d(i, d, s) and
 * lux_sample_2d(i, d, s) are independent of each other for every d.
 * Distinct dimensions use distinct index shuffles, so two dimensions of one
 * texel are decorrelated (padding, Burley §4).
 *
 * Integer arithmetic only, so the same (index, dimension, seed) yields the
 * same bits on every device. Floats are formed from the top 24 bits
 * (x >> 8) * 2^-24: exact, always in [0, 1), and the truncation never moves a
 * point across a dyadic cell boundary, so the stratification survives the
 * conversion exactly (rounding 32 bits to float could round up to 1.0 or
 * across a boundary).
 *
 * Ablation: with LUX_SEQUENCE_RANDOM defined, the same functions return
 * independent hash-based uniform random numbers for (index, dimension, seed). */
#ifndef LUXEL_SAMPLING_SEQUENCE_H
#define LUXEL_SAMPLING_SEQUENCE_H

/* lowbias32 (Wellons, "Hash Prospector", 2018): a bijective 32-bit hash with
 * near-ideal avalanche (bias ~1.7e-4). */
inline uint lux_hash_u32(uint x) {
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return x;
}

/* Order-dependent combination of two words (boost::hash_combine's mixing of
 * a hashed b into a, followed by a full hash so every output bit depends on
 * every input bit). */
inline uint lux_hash_combine(uint a, uint b) {
  return lux_hash_u32(a ^ (lux_hash_u32(b) + 0x9e3779b9u + (a << 6) + (a >> 2)));
}

/* Top 24 bits to a float in [0, 1); see the header comment. */
inline float lux_u32_to_unit_float(uint x) {
  return (float)(x >> 8) * 0x1p-24f;
}

/* Per-(seed, dimension) base seed; `arity` (1 or 2) keeps 1D and 2D
 * dimensions apart. */
inline uint lux_sequence_seed(uint seed, uint dimension, uint arity) {
  return lux_hash_combine(lux_hash_combine(seed, dimension), arity);
}

#if LUX_SEQUENCE_RANDOM

inline float lux_sample_1d(uint index, uint dimension, uint seed) {
  return lux_u32_to_unit_float(lux_hash_combine(lux_sequence_seed(seed, dimension, 1u), index));
}

inline float2 lux_sample_2d(uint index, uint dimension, uint seed) {
  const uint h = lux_hash_combine(lux_sequence_seed(seed, dimension, 2u), index);
  return (float2)(lux_u32_to_unit_float(h), lux_u32_to_unit_float(lux_hash_u32(h ^ 0xa511e9b3u)));
}

#else

/* Bit reversal. Clang (PoCL's compiler) has it as one intrinsic, which
 * x86 lowers to a byte swap and three masked steps instead of five; the
 * shifts below are the same function for the other compilers. */
inline uint lux_reverse_bits(uint x) {
#ifdef __has_builtin
#if __has_builtin(__builtin_bitreverse32)
  return __builtin_bitreverse32(x);
#endif
#endif
  x = (x << 16) | (x >> 16);
  x = ((x & 0x00ff00ffu) << 8) | ((x & 0xff00ff00u) >> 8);
  x = ((x & 0x0f0f0f0fu) << 4) | ((x & 0xf0f0f0f0u) >> 4);
  x = ((x & 0x33333333u) << 2) | ((x & 0xccccccccu) >> 2);
  x = ((x & 0x55555555u) << 1) | ((x & 0xaaaaaaaau) >> 1);
  return x;
}

/* Laine-Karras permutation: each output bit is its input bit flipped by a
 * function of the LOWER bits only (additions and multiplications carry
 * upwards), which is exactly a nested uniform scramble of the bit-reversed
 * number. Constants: Vegdahl 2021. */
inline uint lux_lk_permutation(uint x, uint seed) {
  x ^= x * 0x3d20adeau;
  x += seed;
  x *= (seed >> 16) | 1u;
  x ^= x * 0x05526c56u;
  x ^= x * 0x53a22864u;
  return x;
}

/* Owen scramble of x read as a binary fraction (bit 31 = 1/2): every bit is
 * flipped by a hash of the bits above it (Burley 2020, Listing 2). */
inline uint lux_nested_uniform_scramble(uint x, uint seed) {
  return lux_reverse_bits(lux_lk_permutation(lux_reverse_bits(x), seed));
}

/* Sobol dimension 1 (direction numbers v_{k+1} = v_k ^ (v_k >> 1)); dimension
 * 0 is the van der Corput sequence, reverse_bits(index).
 *
 * Direction number v_k has bit 31 - j set iff C(k, j) is odd, which by
 * Lucas' theorem means j is a bit-subset of k. So bit 31 - j of the result
 * is the XOR of index bit k over the supersets k of j: a superset (zeta)
 * transform over the 5 bits of a bit position, one shift-XOR per bit, then
 * a reversal. The same bits as the 32-step loop over direction numbers
 * (tests/unit/kernels/sampling/sequence_test.cpp), without its branches. */
inline uint lux_sobol_dim1(uint index) {
  uint c = index;
  c ^= (c >> 1) & 0x55555555u;
  c ^= (c >> 2) & 0x33333333u;
  c ^= (c >> 4) & 0x0f0f0f0fu;
  c ^= (c >> 8) & 0x00ff00ffu;
  c ^= (c >> 16) & 0x0000ffffu;
  return lux_reverse_bits(c);
}

inline float lux_sample_1d(uint index, uint dimension, uint seed) {
  const uint s = lux_sequence_seed(seed, dimension, 1u);
  const uint shuffled = lux_nested_uniform_scramble(index, lux_hash_combine(s, 0u));
  const uint x = lux_nested_uniform_scramble(lux_reverse_bits(shuffled), lux_hash_combine(s, 1u));
  return lux_u32_to_unit_float(x);
}

inline float2 lux_sample_2d(uint index, uint dimension, uint seed) {
  const uint s = lux_sequence_seed(seed, dimension, 2u);
  const uint shuffled = lux_nested_uniform_scramble(index, lux_hash_combine(s, 0u));
  const uint x = lux_nested_uniform_scramble(lux_reverse_bits(shuffled), lux_hash_combine(s, 1u));
  const uint y = lux_nested_uniform_scramble(lux_sobol_dim1(shuffled), lux_hash_combine(s, 2u));
  return (float2)(lux_u32_to_unit_float(x), lux_u32_to_unit_float(y));
}

#endif /* LUX_SEQUENCE_RANDOM */

#endif /* LUXEL_SAMPLING_SEQUENCE_H */
