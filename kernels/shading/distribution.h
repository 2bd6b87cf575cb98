/* Piecewise-constant distributions stored as normalised CDFs (device side).
 *
 * A distribution over n cells is n + 1 floats: cdf[0] = 0, non-decreasing,
 * cdf[n] = 1 (built on the host by shading/cdf.h). The
 * probability of cell i is cdf[i+1] - cdf[i]; sampling and pdf evaluation
 * both read that same float difference, so a sample's pmf and the pmf the
 * MIS code evaluates later are always identical. Used for the equirect sky
 * (2D: marginal over rows, one conditional per row). Light selection by power
 * (thesis §6.3.2) uses an alias table instead (lux_sample_alias): O(1) in the
 * number of lights, where the binary search is O(log n). */
#ifndef LUXEL_SHADING_DISTRIBUTION_H
#define LUXEL_SHADING_DISTRIBUTION_H

#include "shared/light.h"

/* The largest float below 1: u is clamped to it so u = 1 cannot run off the
 * end of the table. */
#define LUX_ONE_MINUS_EPSILON 0x1.fffffep-1f

/* Binary search: the cell i with cdf[i] <= u < cdf[i+1]. Zero-width cells are
 * never returned (the search takes the largest i with cdf[i] <= u, whose
 * successor is therefore > u). *pmf = cdf[i+1] - cdf[i]. n >= 1. */
inline uint lux_sample_cdf(const __global float* cdf, uint n, float u, float* pmf) {
  u = clamp(u, 0.0f, LUX_ONE_MINUS_EPSILON);
  uint lo = 0, hi = n; /* invariant: cdf[lo] <= u, answer in [lo, hi) */
  while (hi - lo > 1u) {
    const uint mid = (lo + hi) >> 1;
    if (cdf[mid] <= u)
      lo = mid;
    else
      hi = mid;
  }
  *pmf = cdf[lo + 1] - cdf[lo];
  return lo;
}

/* Where u fell inside cell i, in [0, 1): reuses the low bits of u for the
 * position within the cell (pbrt's Distribution1D::SampleContinuous). */
inline float lux_cdf_remap(const __global float* cdf, uint i, float u) {
  const float width = cdf[i + 1] - cdf[i];
  const float t = width > 0.0f ? (u - cdf[i]) / width : 0.5f;
  return clamp(t, 0.0f, LUX_ONE_MINUS_EPSILON);
}

/* Alias-table selection (shared/light.h, LuxAliasEntry): one cell read and
 * at most one more for the pmf of the alias, whatever the table's size.
 * *pmf is the chosen entry's probability; n >= 1. */
inline uint lux_sample_alias(const __global LuxAliasEntry* table, uint n, float u, float* pmf) {
  const float scaled = clamp(u, 0.0f, LUX_ONE_MINUS_EPSILON) * (float)n;
  const uint cell = min((uint)scaled, n - 1u);
  const LuxAliasEntry e = table[cell];
  const uint chosen = scaled - (float)cell < e.threshold ? cell : e.alias;
  *pmf = chosen == cell ? e.pmf : table[chosen].pmf;
  return chosen;
}

/* Probability of cell i. */
inline float lux_cdf_pmf(const __global float* cdf, uint i) {
  return cdf[i + 1] - cdf[i];
}

/* 2D sampling over a width x height grid (row-major): picks a row from the
 * marginal with u.y, a column from that row's conditional with u.x. Returns
 * continuous (s, t) in [0,1)^2 (s along a row, t down the rows) and the
 * density with respect to (s, t). */
inline float2 lux_sample_grid_2d(const __global float* marginal, const __global float* conditional,
                                 uint width, uint height, float2 u, float* pdf_st) {
  float pm, pc;
  const uint row = lux_sample_cdf(marginal, height, u.y, &pm);
  const float t =
      ((float)row + lux_cdf_remap(marginal, row, clamp(u.y, 0.0f, LUX_ONE_MINUS_EPSILON))) /
      (float)height;
  const __global float* cond = conditional + (size_t)row * (width + 1u);
  const uint col = lux_sample_cdf(cond, width, u.x, &pc);
  const float s = ((float)col + lux_cdf_remap(cond, col, clamp(u.x, 0.0f, LUX_ONE_MINUS_EPSILON))) /
                  (float)width;
  *pdf_st = pm * (float)height * pc * (float)width;
  return (float2)(s, t);
}

/* The density lux_sample_grid_2d has at (s, t). */
inline float lux_pdf_2d(const __global float* marginal, const __global float* conditional,
                        uint width, uint height, float2 st) {
  const uint col = min((uint)max(st.x * (float)width, 0.0f), width - 1u);
  const uint row = min((uint)max(st.y * (float)height, 0.0f), height - 1u);
  const __global float* cond = conditional + (size_t)row * (width + 1u);
  return lux_cdf_pmf(marginal, row) * (float)height * lux_cdf_pmf(cond, col) * (float)width;
}

#endif /* LUXEL_SHADING_DISTRIBUTION_H */
