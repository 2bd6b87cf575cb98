#include "lightmap_agreement.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace luxel::test {
namespace {

using reference::Comparison;
using reference::Estimate;

double luminance(const float* rgb) {
  return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
}

// Engine estimate of texel t, channel c (0-2 colour, 3 luminance): mean of
// the replicas and the standard error from their spread.
Estimate engine_estimate(const EngineBakes& e, size_t t, int c) {
  double sum = 0, sum2 = 0;
  for (const auto& r : e.replicas) {
    const float* px = &r.irradiance[t * 4];
    const double v = c < 3 ? double{px[c]} : luminance(px);
    sum += v;
    sum2 += v * v;
  }
  const double n = static_cast<double>(e.replicas.size()), mean = sum / n;
  const double var = std::max(0.0, (sum2 - n * mean * mean) / (n - 1));
  return {mean, std::sqrt(var / n), n - 1};
}

Estimate reference_estimate(const reference::ReferenceLightmap& ref, size_t t, int c,
                            double scale) {
  return {ref.mean_of(t, c) * scale, ref.std_error(t, c) * scale,
          static_cast<double>(ref.samples[t]) - 1};
}

}  // namespace

bool Summary::pooled_test_fails() const {
  return std::abs(pooled_z) >
         reference::two_sided_critical(kFamilyAlpha, reference::kKnownVariance);
}

std::vector<size_t> fully_covered_texels(const EngineBakes& e) {
  std::vector<size_t> tested;
  const pipeline::BakeResult& e0 = e.replicas.front();
  for (size_t t = 0; t < e0.irradiance.size() / 4; ++t)
    if (e0.irradiance[t * 4 + 3] == 1.0f) tested.push_back(t);
  return tested;
}

Summary compare_bakes(const EngineBakes& e, const reference::ReferenceLightmap& ref,
                      double reference_scale, const std::vector<size_t>& texels) {
  Summary s;
  const pipeline::BakeResult& e0 = e.replicas.front();
  for (size_t t = 0; t < e0.irradiance.size() / 4; ++t)
    if (e0.irradiance[t * 4 + 3] > 0) ++s.covered;
  s.replicas = e.replicas.size();
  s.tested = texels.size();
  s.tests = texels.size() * 3;
  s.alpha_per_test = reference::sidak_alpha(kFamilyAlpha, s.tests);
  const double replicas = static_cast<double>(e.replicas.size());
  double sum_e = 0, var_e = 0, sum_r = 0, var_r = 0, t2 = 0, self_var = 0;
  size_t nonblack = 0;
  std::vector<double> rel_se;
  for (size_t t : texels) {
    for (int c = 0; c < 3; ++c) {
      const Comparison cmp = reference::compare(engine_estimate(e, t, c),
                                                reference_estimate(ref, t, c, reference_scale));
      t2 += cmp.t * cmp.t;
      if (cmp.p_value < s.alpha_per_test) ++s.failures;
      if (std::abs(cmp.t) > s.max_abs_t) {
        s.max_abs_t = std::abs(cmp.t);
        s.worst_texel = t;
        s.worst_channel = c;
      }
    }
    const Estimate ey = engine_estimate(e, t, 3);
    const Estimate ry = reference_estimate(ref, t, 3, reference_scale);
    sum_e += ey.mean;
    var_e += ey.std_error * ey.std_error;
    sum_r += ry.mean;
    var_r += ry.std_error * ry.std_error;
    if (ey.mean > 0 && ry.mean > 0) {
      ++nonblack;
      rel_se.push_back(std::hypot(ey.std_error, ry.std_error) / ry.mean);
    }
    // The engine's own luminance error of each replica: rel_error * mean.
    double self = 0;
    for (const auto& r : e.replicas) {
      const double se = double{r.rel_error[t]} * luminance(&r.irradiance[t * 4]);
      self += se * se;
    }
    self_var += self / (replicas * replicas);
  }
  const double n = std::max<double>(1.0, static_cast<double>(s.tested));
  s.mean_t2 = s.tests > 0 ? t2 / static_cast<double>(s.tests) : 0;
  s.engine_mean_y = sum_e / n;
  s.ref_mean_y = sum_r / n;
  s.nonblack_fraction = static_cast<double>(nonblack) / n;
  if (!rel_se.empty()) {
    std::nth_element(rel_se.begin(), rel_se.begin() + static_cast<long>(rel_se.size() / 2),
                     rel_se.end());
    s.median_rel_se = rel_se[rel_se.size() / 2];
  }
  s.ratio = sum_r > 0 ? sum_e / sum_r : 0;
  s.ratio_se = sum_e > 0 && sum_r > 0
                   ? s.ratio * std::sqrt(var_e / (sum_e * sum_e) + var_r / (sum_r * sum_r))
                   : 0;
  s.pooled_z = var_e + var_r > 0 ? (sum_e - sum_r) / std::sqrt(var_e + var_r) : 0;
  s.engine_share = var_e + var_r > 0 ? var_e / (var_e + var_r) : 0;
  s.self_se_ratio = var_e > 0 ? std::sqrt(self_var / var_e) : 0;
  return s;
}

RatioOfRatios ratio_of_ratios(const Summary& a, const Summary& b) {
  RatioOfRatios r;
  if (!(a.ratio > 0 && b.ratio > 0)) return r;
  r.ratio = a.ratio / b.ratio;
  r.se = r.ratio * std::hypot(a.ratio_se / a.ratio, b.ratio_se / b.ratio);
  r.z = r.se > 0 ? (r.ratio - 1.0) / r.se : 0;
  return r;
}

void print_summary(const char* title, const EngineBakes& e, const reference::ReferenceLightmap& ref,
                   const Summary& s) {
  const size_t w = static_cast<size_t>(ref.width);
  std::printf("\n%s\n", title);
  std::printf("  %-34s %18s %18s\n", "", "engine", "reference (CPU)");
  std::printf("  %-34s %18llu %18llu\n", "paths", static_cast<unsigned long long>(e.paths),
              static_cast<unsigned long long>(ref.paths));
  std::printf("  %-34s %18.2f %18.2f\n", "seconds", e.seconds, ref.seconds);
  std::printf("  %-34s %18.2f %18.2f\n", "M paths/s",
              static_cast<double>(e.paths) / e.seconds * 1e-6,
              static_cast<double>(ref.paths) / ref.seconds * 1e-6);
  std::printf("  %-34s %18.5f %18.5f\n", "mean luminance (tested texels)", s.engine_mean_y,
              s.ref_mean_y);
  std::printf("  tested texels (alpha == 1)          %zu of %zu covered, %zu tests (RGB)\n",
              s.tested, s.covered, s.tests);
  std::printf("  Sidak alpha per test                %.3g (family %.0e)\n", s.alpha_per_test,
              kFamilyAlpha);
  std::printf("  max |t|                             %.2f at texel (%zu, %zu) channel %d\n",
              s.max_abs_t, s.worst_texel % w, s.worst_texel / w, s.worst_channel);
  // Welch's degrees of freedom lie between the replicas' (R - 1) and infinity.
  std::printf("  critical |t|                        %.2f (dof inf) .. %.2f (dof %zu)\n",
              reference::two_sided_critical(s.alpha_per_test, reference::kKnownVariance),
              reference::two_sided_critical(s.alpha_per_test, static_cast<double>(s.replicas - 1)),
              s.replicas - 1);
  std::printf("  failing tests                       %zu\n", s.failures);
  std::printf("  mean t^2                            %.3f\n", s.mean_t2);
  std::printf("  median relative se (per texel, Y)   %.4f\n", s.median_rel_se);
  std::printf("  pooled ratio engine / reference     %.5f +- %.5f (z %.2f, critical %.2f)\n",
              s.ratio, s.ratio_se, s.pooled_z,
              reference::two_sided_critical(kFamilyAlpha, reference::kKnownVariance));
  std::printf("  engine share of the pooled variance %.3f\n", s.engine_share);
  std::printf("  engine rel_error se / replica se    %.3f (RMS over tested texels, luminance)\n",
              s.self_se_ratio);
  std::printf("  device                              %s\n", e.device.c_str());
}

void expect_same_texel_domain(const EngineBakes& e, const reference::ReferenceLightmap& ref,
                              const atlas::Atlas& atlas, uint32_t engine_spp,
                              uint32_t reference_spp) {
  for (const auto& r : e.replicas) {
    ASSERT_EQ(r.width, ref.width);
    ASSERT_EQ(r.height, ref.height);
    ASSERT_EQ(r.atlas.mode, atlas.mode);
    ASSERT_EQ(r.atlas.placements.size(), atlas.placements.size());
    for (size_t i = 0; i < atlas.placements.size(); ++i) {
      for (int k = 0; k < 2; ++k) {
        EXPECT_EQ(r.atlas.placements[i].scale[k], atlas.placements[i].scale[k]);
        EXPECT_EQ(r.atlas.placements[i].offset[k], atlas.placements[i].offset[k]);
      }
    }
    for (size_t t = 0; t < ref.coverage.size(); ++t) {
      ASSERT_EQ(r.irradiance[t * 4 + 3], ref.coverage[t]) << "coverage of texel " << t;
      if (ref.coverage[t] > 0) {
        ASSERT_EQ(r.samples[t], static_cast<float>(engine_spp)) << "texel " << t;
        ASSERT_EQ(ref.samples[t], reference_spp) << "texel " << t;
      }
    }
    EXPECT_EQ(r.nonfinite_dropped, 0u);
  }
}

}  // namespace luxel::test
