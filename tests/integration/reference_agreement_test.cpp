// Agreement of the OpenCL bake engine (pipeline::bake), through each of its
// ray-query backends (Embree on the host, OpenCL traversal), with an
// independent estimator: the CPU reference path tracer of tests/reference,
// on the bundled Cornell box (DESIGN.md, "Accuracy and error reporting": agreement
// between two independent estimators within confidence bounds, z-test with
// Šidák correction over texels; the render tests of Mitsuba 3 do the same).
//
// Both sides integrate over the same texel domain (atlas::build_atlas +
// build_sample_info: a texel's value is the mean irradiance over its valid
// Hammersley positions) with the same light transport (B indirect bounces,
// Lambert, single-sided emitters), but share no sampling or shading code.
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
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "atlas/atlas.h"
#include "device/context.h"
#include "pipeline/bake.h"
#include "reference/agreement_stats.h"
#include "reference/cpu_lightmap_tracer.h"
#include "scene/gltf_import.h"

namespace luxel {
namespace {

using reference::Comparison;
using reference::Estimate;

constexpr const char* kScene = LUXEL_SCENES_DIR "/cornell_box.gltf";
constexpr int kResolution = 32;
constexpr int kMaxBounces = 3;
constexpr int kReplicas = 16;
constexpr uint32_t kEngineSppPerReplica = 128;
constexpr uint32_t kReferenceSpp = 2048;
constexpr double kFamilyAlpha = 1e-3;
constexpr double kInjectedError = 1.03;  // the deliberate error of the second test

double luminance(const float* rgb) {
  return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
}

struct Bakes {
  std::vector<pipeline::BakeResult> engine;  // kReplicas independent bakes
  reference::ReferenceLightmap ref;
  double engine_seconds = 0;
  uint64_t engine_paths = 0;
  std::string device;
};

// Engine estimate of texel t, channel c (0-2 colour, 3 luminance): mean of
// the replicas and the standard error from their spread.
Estimate engine_estimate(const Bakes& b, size_t t, int c) {
  double sum = 0, sum2 = 0;
  for (const auto& r : b.engine) {
    const float* px = &r.irradiance[t * 4];
    const double v = c < 3 ? double{px[c]} : luminance(px);
    sum += v;
    sum2 += v * v;
  }
  const double n = kReplicas, mean = sum / n;
  const double var = std::max(0.0, (sum2 - n * mean * mean) / (n - 1));
  return {mean, std::sqrt(var / n), n - 1};
}

Estimate reference_estimate(const Bakes& b, size_t t, int c, double scale) {
  return {b.ref.mean_of(t, c) * scale, b.ref.std_error(t, c) * scale,
          static_cast<double>(b.ref.samples[t]) - 1};
}

struct Summary {
  size_t covered = 0, tested = 0, tests = 0, failures = 0;
  double alpha_per_test = 0;
  double max_abs_t = 0;
  size_t worst_texel = 0;
  int worst_channel = 0;
  double mean_t2 = 0;                        // mean of t^2 over all tests (~1 when they agree)
  double engine_mean_y = 0, ref_mean_y = 0;  // over tested texels
  double nonblack_fraction = 0;              // tested texels where both sides are > 0
  double median_rel_se = 0;                  // of the combined per-texel luminance error
  double ratio = 0, ratio_se = 0, pooled_z = 0;
  double self_se_ratio = 0;  // engine rel_error-based se / replica se (RMS, luminance)

  bool texel_test_fails() const { return failures > 0; }
  bool pooled_test_fails() const {
    return std::abs(pooled_z) >
           reference::two_sided_critical(kFamilyAlpha, reference::kKnownVariance);
  }
};

Summary compare_bakes(const Bakes& b, double reference_scale) {
  Summary s;
  const pipeline::BakeResult& e0 = b.engine.front();
  std::vector<size_t> tested;
  for (size_t t = 0; t < e0.irradiance.size() / 4; ++t) {
    if (e0.irradiance[t * 4 + 3] <= 0) continue;
    ++s.covered;
    if (e0.irradiance[t * 4 + 3] == 1.0f) tested.push_back(t);  // full coverage only
  }
  s.tested = tested.size();
  s.tests = tested.size() * 3;
  s.alpha_per_test = reference::sidak_alpha(kFamilyAlpha, s.tests);
  double sum_e = 0, var_e = 0, sum_r = 0, var_r = 0, t2 = 0, self_var = 0;
  size_t nonblack = 0;
  std::vector<double> rel_se;
  for (size_t t : tested) {
    for (int c = 0; c < 3; ++c) {
      const Comparison cmp = reference::compare(engine_estimate(b, t, c),
                                                reference_estimate(b, t, c, reference_scale));
      t2 += cmp.t * cmp.t;
      if (cmp.p_value < s.alpha_per_test) ++s.failures;
      if (std::abs(cmp.t) > s.max_abs_t) {
        s.max_abs_t = std::abs(cmp.t);
        s.worst_texel = t;
        s.worst_channel = c;
      }
    }
    const Estimate ey = engine_estimate(b, t, 3);
    const Estimate ry = reference_estimate(b, t, 3, reference_scale);
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
    for (const auto& r : b.engine) {
      const double se = double{r.rel_error[t]} * luminance(&r.irradiance[t * 4]);
      self += se * se;
    }
    self_var += self / (kReplicas * kReplicas);
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
  s.self_se_ratio = var_e > 0 ? std::sqrt(self_var / var_e) : 0;
  return s;
}

void print_summary(const char* title, const Bakes& b, const Summary& s) {
  const size_t w = static_cast<size_t>(b.ref.width);
  std::printf("\n%s\n", title);
  std::printf("  %-34s %18s %18s\n", "", "engine", "reference (CPU)");
  std::printf("  %-34s %18llu %18llu\n", "paths", static_cast<unsigned long long>(b.engine_paths),
              static_cast<unsigned long long>(b.ref.paths));
  std::printf("  %-34s %18.2f %18.2f\n", "seconds", b.engine_seconds, b.ref.seconds);
  std::printf("  %-34s %18.2f %18.2f\n", "M paths/s",
              static_cast<double>(b.engine_paths) / b.engine_seconds * 1e-6,
              static_cast<double>(b.ref.paths) / b.ref.seconds * 1e-6);
  std::printf("  %-34s %18.5f %18.5f\n", "mean luminance (tested texels)", s.engine_mean_y,
              s.ref_mean_y);
  std::printf("  tested texels (alpha == 1)          %zu of %zu covered, %zu tests (RGB)\n",
              s.tested, s.covered, s.tests);
  std::printf("  Sidak alpha per test                %.3g (family %.0e)\n", s.alpha_per_test,
              kFamilyAlpha);
  std::printf("  max |t|                             %.2f at texel (%zu, %zu) channel %d\n",
              s.max_abs_t, s.worst_texel % w, s.worst_texel / w, s.worst_channel);
  // Welch's degrees of freedom lie between the replicas' (R - 1) and infinity.
  std::printf("  critical |t|                        %.2f (dof inf) .. %.2f (dof %d)\n",
              reference::two_sided_critical(s.alpha_per_test, reference::kKnownVariance),
              reference::two_sided_critical(s.alpha_per_test, kReplicas - 1), kReplicas - 1);
  std::printf("  failing tests                       %zu\n", s.failures);
  std::printf("  mean t^2                            %.3f\n", s.mean_t2);
  std::printf("  median relative se (per texel, Y)   %.4f\n", s.median_rel_se);
  std::printf("  pooled ratio engine / reference     %.5f +- %.5f (z %.2f, critical %.2f)\n",
              s.ratio, s.ratio_se, s.pooled_z,
              reference::two_sided_critical(kFamilyAlpha, reference::kKnownVariance));
  std::printf("  engine rel_error se / replica se    %.3f (RMS over tested texels, luminance)\n",
              s.self_se_ratio);
  std::printf("  device                              %s\n", b.device.c_str());
}

class ReferenceAgreement : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    auto scene = scene::import_gltf_file(kScene);
    if (!scene) return fail("import: " + scene.status().to_string());
    auto ctx = device::Context::create();
    if (!ctx) return fail("OpenCL: " + ctx.status().to_string());
    pipeline::BakeSettings settings;
    settings.atlas.resolution = kResolution;
    settings.samples_per_texel = kEngineSppPerReplica;
    settings.max_bounces = kMaxBounces;
    settings.filter = pipeline::Filter::kBox;
    settings.clamp_luminance = 0;  // unbiased
    for (accel::IntersectorKind kind :
         {accel::IntersectorKind::kEmbree, accel::IntersectorKind::kOpenCl}) {
      auto bakes = std::make_unique<Bakes>();
      settings.intersector = kind;
      for (int r = 0; r < kReplicas; ++r) {
        settings.seed = 1000u + static_cast<uint32_t>(r);
        auto result = pipeline::bake(scene.value(), settings, *ctx.value());
        if (!result)
          return fail(strprintf("engine bake (%s, seed %u): ", accel::intersector_name(kind),
                                settings.seed) +
                      result.status().to_string());
        bakes->engine_seconds += result.value().seconds;
        bakes->engine_paths += result.value().paths;
        bakes->device = result.value().device + ", " + result.value().intersector;
        bakes->engine.push_back(std::move(result.value()));
      }
      (kind == accel::IntersectorKind::kEmbree ? embree_ : opencl_) = std::move(bakes);
    }

    // The reference lays out the same atlas itself (the engine's is checked
    // against it in the test) and bakes every covered texel.
    auto atlas = atlas::build_atlas(scene.value(), settings.atlas);
    if (!atlas) return fail("atlas: " + atlas.status().to_string());
    atlas_ = std::make_unique<atlas::Atlas>(std::move(atlas.value()));
    reference::ReferenceSettings ref_settings;
    ref_settings.samples_per_texel = kReferenceSpp;
    ref_settings.max_bounces = kMaxBounces;
    ref_settings.seed = 7;
    ref_settings.threads = 2;
    auto ref = reference::bake_reference(scene.value(), *atlas_, ref_settings);
    if (!ref) return fail("reference: " + ref.status().to_string());
    embree_->ref = ref.value();
    opencl_->ref = std::move(ref.value());
  }
  static void TearDownTestSuite() {
    embree_.reset();
    opencl_.reset();
    atlas_.reset();
  }
  static void fail(const std::string& why) { setup_error_ = why; }

  void SetUp() override {
    ASSERT_TRUE(embree_ && opencl_ && embree_->ref.width > 0) << "setup failed: " << setup_error_;
  }

  static void expect_agreement(const Bakes& b, const char* title);

  static std::unique_ptr<Bakes> embree_, opencl_;
  static std::unique_ptr<atlas::Atlas> atlas_;
  static std::string setup_error_;
};

std::unique_ptr<Bakes> ReferenceAgreement::embree_;
std::unique_ptr<Bakes> ReferenceAgreement::opencl_;
std::unique_ptr<atlas::Atlas> ReferenceAgreement::atlas_;
std::string ReferenceAgreement::setup_error_;

TEST_F(ReferenceAgreement, EmbreeBackendAgreesWithReferenceWithinConfidenceBounds) {
  expect_agreement(*embree_, "Cornell box: engine (Embree) vs CPU reference (32x32, 3 bounces)");
}

TEST_F(ReferenceAgreement, OpenClBackendAgreesWithReferenceWithinConfidenceBounds) {
  expect_agreement(*opencl_, "Cornell box: engine (OpenCL) vs CPU reference (32x32, 3 bounces)");
}

void ReferenceAgreement::expect_agreement(const Bakes& b, const char* title) {
  // Same texel domain: same atlas, same coverage (alpha) per texel.
  for (const auto& e : b.engine) {
    ASSERT_EQ(e.width, b.ref.width);
    ASSERT_EQ(e.height, b.ref.height);
    ASSERT_EQ(e.atlas.mode, atlas_->mode);
    ASSERT_EQ(e.atlas.placements.size(), atlas_->placements.size());
    for (size_t i = 0; i < atlas_->placements.size(); ++i) {
      for (int k = 0; k < 2; ++k) {
        EXPECT_EQ(e.atlas.placements[i].scale[k], atlas_->placements[i].scale[k]);
        EXPECT_EQ(e.atlas.placements[i].offset[k], atlas_->placements[i].offset[k]);
      }
    }
    for (size_t t = 0; t < b.ref.coverage.size(); ++t) {
      ASSERT_EQ(e.irradiance[t * 4 + 3], b.ref.coverage[t]) << "coverage of texel " << t;
      if (b.ref.coverage[t] > 0) {
        ASSERT_EQ(e.samples[t], static_cast<float>(kEngineSppPerReplica)) << "texel " << t;
        ASSERT_EQ(b.ref.samples[t], kReferenceSpp) << "texel " << t;
      }
    }
    EXPECT_EQ(e.nonfinite_dropped, 0u);
  }

  const Summary s = compare_bakes(b, 1.0);
  print_summary(title, b, s);
  // Not trivially passing: a lit lightmap, enough texels, errors small
  // enough that the per-texel test has teeth.
  EXPECT_GE(s.tested, 200u);
  EXPECT_GT(s.ref_mean_y, 0.05);
  EXPECT_GT(s.nonblack_fraction, 0.9);
  EXPECT_LT(s.median_rel_se, 0.05);
  // The tests themselves.
  EXPECT_EQ(s.failures, 0u) << "worst texel (" << s.worst_texel % static_cast<size_t>(b.ref.width)
                            << ", " << s.worst_texel / static_cast<size_t>(b.ref.width)
                            << ") channel " << s.worst_channel << ": |t| " << s.max_abs_t;
  EXPECT_FALSE(s.pooled_test_fails())
      << "pooled ratio " << s.ratio << " +- " << s.ratio_se << " (z " << s.pooled_z << ")";
}

TEST_F(ReferenceAgreement, DetectsDeliberateThreePercentError) {
  const Bakes& b = *embree_;
  const Summary s = compare_bakes(b, kInjectedError);
  print_summary("Same comparison, reference scaled by 1.03 (deliberate error)", b, s);
  EXPECT_TRUE(s.texel_test_fails() || s.pooled_test_fails())
      << "a 3 % error went unnoticed: max |t| " << s.max_abs_t << ", pooled z " << s.pooled_z;
  // The pooled ratio sees the error for what it is.
  EXPECT_NEAR(s.ratio, 1.0 / kInjectedError, 6 * s.ratio_se);
}

}  // namespace
}  // namespace luxel
