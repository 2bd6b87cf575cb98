// Texel-by-texel comparison of engine bakes (pipeline::bake, R replicas with
// different seeds) with a CPU reference lightmap (tests/reference), shared by
// the agreement tests of this folder.
//
// Standard errors:
//   reference  the sample variance of its own independent paths per texel
//              (n - 1 degrees of freedom, effectively known).
//   engine     from R independent replicas (bakes with different seeds).
//              BakeResult only reports a luminance error (rel_error, from
//              the Welford variance of the texel's paths), and the engine
//              samples an Owen-scrambled Sobol sequence per texel, for which
//              that i.i.d. variance is not the variance of the mean. Replicas
//              are independent randomisations, so the spread of their means
//              is an unbiased variance estimate for every colour channel
//              (R - 1 degrees of freedom). The rel_error-based luminance
//              error is reported beside it as a calibration figure.
// Per texel and colour channel, Welch's t = (a - b) / sqrt(se_a^2 + se_b^2)
// is tested two-sided at the Šidák level for the whole family (alpha_family
// = 1e-3), with Welch-Satterthwaite degrees of freedom. A pooled test on the
// sum of luminance over all tested texels (texels are independent) adds a
// sensitive guard: its standard error is ~1/sqrt(texels) of a texel's.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "atlas/atlas.h"
#include "bake/bake.h"
#include "reference/agreement_stats.h"
#include "reference/cpu_lightmap_tracer.h"

namespace luxel::test {

constexpr double kFamilyAlpha = 1e-3;

struct EngineBakes {
  std::vector<pipeline::BakeResult> replicas;  // independent bakes (different seeds)
  double seconds = 0;
  uint64_t paths = 0;
  std::string device;
};

struct Summary {
  size_t covered = 0, tested = 0, tests = 0, failures = 0;
  size_t replicas = 0;
  double alpha_per_test = 0;
  double max_abs_t = 0;
  size_t worst_texel = 0;
  int worst_channel = 0;
  double mean_t2 = 0;                        // mean of t^2 over all tests (~1 when they agree)
  double engine_mean_y = 0, ref_mean_y = 0;  // over tested texels
  double nonblack_fraction = 0;              // tested texels where both sides are > 0
  double median_rel_se = 0;                  // of the combined per-texel luminance error
  double ratio = 0, ratio_se = 0, pooled_z = 0;
  double engine_share = 0;   // of the pooled variance (the rest is the reference's)
  double self_se_ratio = 0;  // engine rel_error-based se / replica se (RMS, luminance)

  bool texel_test_fails() const { return failures > 0; }
  bool pooled_test_fails() const;
};

// Texels with full coverage (alpha == 1) in the engine's first replica.
std::vector<size_t> fully_covered_texels(const EngineBakes& e);

// Per-texel Welch tests (Šidák over the 3 colour tests of every texel in
// `texels`) and the pooled luminance ratio over `texels`; the reference is
// multiplied by `reference_scale` (a deliberate error when not 1).
Summary compare_bakes(const EngineBakes& e, const reference::ReferenceLightmap& ref,
                      double reference_scale, const std::vector<size_t>& texels);

// Engine / reference ratio of two pooled ratios (e.g. corners against the
// interior) with its standard error (delta method; the two sets of texels
// are disjoint, so independent) and z = (ratio - 1) / se.
struct RatioOfRatios {
  double ratio = 0, se = 0, z = 0;
};
RatioOfRatios ratio_of_ratios(const Summary& a, const Summary& b);

void print_summary(const char* title, const EngineBakes& e, const reference::ReferenceLightmap& ref,
                   const Summary& s);

// Same texel domain on both sides: same atlas placements and coverage, and
// the sample counts asked for (gtest expectations).
void expect_same_texel_domain(const EngineBakes& e, const reference::ReferenceLightmap& ref,
                              const atlas::Atlas& atlas, uint32_t engine_spp,
                              uint32_t reference_spp);

}  // namespace luxel::test
