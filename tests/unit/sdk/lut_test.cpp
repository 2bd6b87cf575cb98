// The committed client/sdk/luxel_ad_specular_lut.h against a fresh in-process
// regeneration of some of its cells (Listing 8.2) with fewer samples: the
// committed file must be what the generator produces, within Monte Carlo
// tolerance, and the generator must be deterministic.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "luxel_ad_specular_lut.h"
#define LUXEL_AD_LUT_NO_MAIN
#include "ggx_truth.h"
#include "make_ad_specular_lut.cpp"  // the generator's functions, without main

namespace {

// Mean and max |committed - regenerated| over every third cell (121 of 1024
// at 32 x 32, corners included); alpha_shift compares against the cell
// alpha_shift rows away instead, a deliberately wrong expectation.
struct Diff {
  double max = 0.0, mean = 0.0;
};
Diff compare_with_regeneration(int samples, uint64_t seed, int alpha_shift) {
  Diff d;
  int n = 0;
  for (int j = 0; j + alpha_shift < LUXEL_AD_LUT_SIZE_ALPHA; j += 3)
    for (int i = 0; i < LUXEL_AD_LUT_SIZE_NDOTV; i += 3) {
      const double ndotv = (i + 0.5) / LUXEL_AD_LUT_SIZE_NDOTV,
                   alpha = (j + 0.5) / LUXEL_AD_LUT_SIZE_ALPHA;
      const luxel_sdk::DfgScale g = luxel_sdk::integrate_ad_dfg(ndotv, alpha, samples, seed);
      const float* cell =
          &luxel_ad_specular_lut[2 * ((j + alpha_shift) * LUXEL_AD_LUT_SIZE_NDOTV + i)];
      for (double diff : {g.f0 - cell[0], g.f90 - cell[1]}) {
        d.max = std::max(d.max, std::abs(diff));
        d.mean += std::abs(diff);
        ++n;
      }
    }
  d.mean /= n;
  return d;
}

TEST(SdkAdLut, CommittedTableMatchesRegeneration) {
  // 2048 samples and another seed against the committed 65536: the
  // difference is the low-sample run's Monte Carlo error. Measured max
  // 5.0e-4, mean 1.1e-4 (table values span 0 .. 1.03).
  const Diff d = compare_with_regeneration(2048, 7, 0);
  std::printf("LUT regeneration (2048 samples) vs committed: max |diff| %.3g, mean %.3g\n", d.max,
              d.mean);
  EXPECT_LT(d.max, 2e-3);
  EXPECT_LT(d.mean, 3e-4);
  // The tolerances discriminate: one alpha row off fails them.
  const Diff wrong = compare_with_regeneration(2048, 7, 1);
  std::printf("LUT vs regeneration one alpha row off: max %.3g, mean %.3g\n", wrong.max,
              wrong.mean);
  EXPECT_GT(wrong.max, 2e-3);
  EXPECT_GT(wrong.mean, 3e-4);
}

TEST(SdkAdLut, VisibleNormalEstimatorMatchesNdfSampling) {
  // White furnace (L = 1, F = 1): the generator's VNDF sampling with the
  // G2 / G1 weight against ggx_truth.h's independent NDF sampling. This is
  // what caught Listing 8.2's printed G2 * G1 weight (0.09 instead of 0.86 at
  // alpha 0.5, n.v 0.1).
  for (double alpha : {0.1, 0.5, 1.0})
    for (double ndv : {0.1, 0.5, 0.9}) {
      const luxel_sdk::D3 v{0, std::sqrt(1 - ndv * ndv), ndv};
      const int samples = 8192;
      double vndf = 0.0;
      for (int k = 0; k < samples; ++k) {
        const luxel_sdk::D3 h = luxel_sdk::sample_ggx_vndf(
            v, alpha, luxel_sdk::radical_inverse2(uint32_t(k)), (k + 0.5) / samples);
        const luxel_sdk::D3 l = luxel_sdk::reflect_about(v, h);
        if (l.z > 0.0) vndf += luxel_sdk::g2_over_g1(v, l, h, alpha) / samples;
      }
      const double ndf = luxel_test::ggx_specular_truth([](luxel_test::D3) { return 1.0; },
                                                        {v.x, v.y, v.z}, alpha, 1, 1, samples);
      EXPECT_NEAR(vndf, ndf, 3e-3) << "alpha " << alpha << " n.v " << ndv;
    }
}

TEST(SdkAdLut, GeneratorIsDeterministicAndWritesAHeader) {
  luxel_sdk::AdLutSettings s;
  s.size_ndotv = 4;
  s.size_alpha = 3;
  s.samples = 256;
  const std::vector<float> a = luxel_sdk::generate_ad_specular_lut(s),
                           b = luxel_sdk::generate_ad_specular_lut(s);
  EXPECT_EQ(a, b);
  const std::string text = luxel_sdk::ad_lut_header(a, s);
  EXPECT_NE(text.find("#define LUXEL_AD_LUT_SIZE_NDOTV 4"), std::string::npos);
  EXPECT_NE(text.find("#define LUXEL_AD_LUT_SIZE_ALPHA 3"), std::string::npos);
  EXPECT_NE(text.find("--samples 256"), std::string::npos);
}

TEST(SdkAdLut, ExactForTheDominantLobe) {
  // By construction (Listing 8.2) fit * LUT reproduces the ground truth for a
  // lobe at the GGX dominant direction at every cell centre.
  const double ndotv = (10 + 0.5) / LUXEL_AD_LUT_SIZE_NDOTV,
               alpha = (20 + 0.5) / LUXEL_AD_LUT_SIZE_ALPHA;
  const luxel_sdk::D3 n{0, 0, 1}, v{0, std::sqrt(1 - ndotv * ndotv), ndotv};
  const luxel_sdk::D3 r = luxel_sdk::reflect_about(v, n);
  const luxel_sdk::D3 lobe = luxel_sdk::ggx_dominant_direction(n, r, alpha);
  const float coeff = 1.0f, dir[3] = {float(lobe.x), float(lobe.y), float(lobe.z)};
  const float* cell = &luxel_ad_specular_lut[2 * (20 * LUXEL_AD_LUT_SIZE_NDOTV + 10)];
  const float est = luxel_ad_specular(&coeff, 1, dir, 1, 0, 0, 1, float(v.x), float(v.y),
                                      float(v.z), float(alpha), cell[0], cell[1], 1.0f, 1.0f);
  const luxel_sdk::DfgScale d = luxel_sdk::integrate_ad_dfg(ndotv, alpha, 4096, 11);
  const double fitted =
      luxel_ad_specular_lobe(float(dot(n, lobe)), float(dot(r, lobe)), float(alpha));
  EXPECT_NEAR(est, (d.f0 + d.f90) * fitted, 0.01 * est);
}

}  // namespace
