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
// Standard errors and the tests: lightmap_agreement.h (Welch t per texel and
// channel, Šidák over the family, plus a pooled luminance ratio).
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "atlas/atlas.h"
#include "bake/bake.h"
#include "device/context.h"
#include "lightmap_agreement.h"
#include "reference/cpu_lightmap_tracer.h"
#include "scene/gltf_import.h"
#include "support/device_context.h"

namespace luxel {
namespace {

using test::EngineBakes;
using test::Summary;

constexpr const char* kScene = LUXEL_SCENES_DIR "/cornell_box.gltf";
constexpr int kResolution = 32;
constexpr int kMaxBounces = 3;
constexpr int kReplicas = 16;
constexpr uint32_t kEngineSppPerReplica = 128;
constexpr uint32_t kReferenceSpp = 2048;
constexpr double kInjectedError = 1.03;  // the deliberate error of the second test

struct Bakes {
  EngineBakes engine;  // kReplicas independent bakes
  reference::ReferenceLightmap ref;
};

Summary compare_bakes(const Bakes& b, double reference_scale) {
  return test::compare_bakes(b.engine, b.ref, reference_scale,
                             test::fully_covered_texels(b.engine));
}

void print_summary(const char* title, const Bakes& b, const Summary& s) {
  test::print_summary(title, b.engine, b.ref, s);
}

class ReferenceAgreement : public testing::DeviceTest<> {
 protected:
  static void SetUpTestSuite() {
    auto scene = scene::import_gltf_file(kScene);
    if (!scene) return fail("import: " + scene.status().to_string());
    ASSERT_NO_FATAL_FAILURE(DeviceTest::SetUpTestSuite());
    pipeline::BakeSettings settings;
    settings.atlas.resolution = kResolution;
    settings.samples_per_texel = kEngineSppPerReplica;
    settings.max_bounces = kMaxBounces;
    settings.filter = pipeline::Filter::kBox;
    settings.clamp_luminance = 0;  // unbiased
    settings.adaptive = false;     // every texel the same samples, as the reference's
    // Embree, the OpenCL traversal, and Embree with the radiance cache
    // (kernels/bake/radiance_cache.h), whose replicas' spread includes the
    // cache's own noise, shared by neighbouring texels within a replica.
    struct Variant {
      accel::IntersectorKind kind;
      bool cache, guiding;
      std::unique_ptr<Bakes>* out;
    };
    for (const Variant& v : {Variant{accel::IntersectorKind::kEmbree, false, false, &embree_},
                             Variant{accel::IntersectorKind::kOpenCl, false, false, &opencl_},
                             Variant{accel::IntersectorKind::kEmbree, true, false, &cached_},
                             Variant{accel::IntersectorKind::kEmbree, false, true, &guided_}}) {
      auto bakes = std::make_unique<Bakes>();
      const accel::IntersectorKind kind = v.kind;
      settings.intersector = kind;
      settings.radiance_cache = v.cache;
      settings.guiding = v.guiding;
      // The cache and the guide are read as earlier iterations left them:
      // 12 iterations instead of one batch of the device's size.
      settings.paths_per_iteration = v.cache || v.guiding ? 8192 : 0;
      for (int r = 0; r < kReplicas; ++r) {
        settings.seed = 1000u + static_cast<uint32_t>(r);
        auto result = pipeline::bake(scene.value(), settings, *ctx_);
        if (!result)
          return fail(strprintf("engine bake (%s, seed %u): ", choice_name(kind), settings.seed) +
                      result.status().to_string());
        bakes->engine.seconds += result.value().seconds;
        bakes->engine.paths += result.value().paths;
        bakes->engine.device = result.value().device + ", " + result.value().intersector;
        bakes->engine.replicas.push_back(std::move(result.value()));
      }
      *v.out = std::move(bakes);
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
    cached_->ref = ref.value();
    guided_->ref = ref.value();
    opencl_->ref = std::move(ref.value());
  }
  static void TearDownTestSuite() {
    embree_.reset();
    opencl_.reset();
    cached_.reset();
    guided_.reset();
    atlas_.reset();
    DeviceTest::TearDownTestSuite();
  }
  static void fail(const std::string& why) { setup_error_ = why; }

  void SetUp() override {
    ASSERT_TRUE(embree_ && opencl_ && cached_ && guided_ && embree_->ref.width > 0)
        << "setup failed: " << setup_error_;
  }

  static void expect_agreement(const Bakes& b, const char* title);

  static std::unique_ptr<Bakes> embree_, opencl_, cached_, guided_;
  static std::unique_ptr<atlas::Atlas> atlas_;
  static std::string setup_error_;
};

std::unique_ptr<Bakes> ReferenceAgreement::embree_;
std::unique_ptr<Bakes> ReferenceAgreement::opencl_;
std::unique_ptr<Bakes> ReferenceAgreement::cached_;
std::unique_ptr<Bakes> ReferenceAgreement::guided_;
std::unique_ptr<atlas::Atlas> ReferenceAgreement::atlas_;
std::string ReferenceAgreement::setup_error_;

TEST_F(ReferenceAgreement, EmbreeBackendAgreesWithReferenceWithinConfidenceBounds) {
  expect_agreement(*embree_, "Cornell box: engine (Embree) vs CPU reference (32x32, 3 bounces)");
}

TEST_F(ReferenceAgreement, OpenClBackendAgreesWithReferenceWithinConfidenceBounds) {
  expect_agreement(*opencl_, "Cornell box: engine (OpenCL) vs CPU reference (32x32, 3 bounces)");
}

// The radiance cache gathers at most of these 128-spp paths' first hits
// (its share falls only past 64 spp), on 32^2 texels whose averages span
// the box's corners and the light's penumbrae: its bias, if any, is at its
// largest here, against an estimator that shares none of its code.
TEST_F(ReferenceAgreement, RadianceCacheAgreesWithReferenceWithinConfidenceBounds) {
  ASSERT_NE(cached_->engine.replicas[0].features.find("radiance_cache"), std::string::npos);
  ASSERT_TRUE(cached_->engine.replicas[0].irradiance != embree_->engine.replicas[0].irradiance)
      << "the cache gathered nothing";
  expect_agreement(*cached_,
                   "Cornell box: engine (Embree, radiance cache) vs CPU reference (32x32, 3 "
                   "bounces)");
}

// First-bounce guiding: 128 spp per texel reach the fourth epoch (samples
// 32-63 sample from the first two epochs' histogram, 64-127 from three).
TEST_F(ReferenceAgreement, GuidingAgreesWithReferenceWithinConfidenceBounds) {
  ASSERT_NE(guided_->engine.replicas[0].features.find("guiding"), std::string::npos);
  ASSERT_TRUE(guided_->engine.replicas[0].irradiance != embree_->engine.replicas[0].irradiance)
      << "the guide sampled nothing";
  expect_agreement(*guided_,
                   "Cornell box: engine (Embree, guiding) vs CPU reference (32x32, 3 bounces)");
}

void ReferenceAgreement::expect_agreement(const Bakes& b, const char* title) {
  // Same texel domain: same atlas, same coverage (alpha) per texel.
  test::expect_same_texel_domain(b.engine, b.ref, *atlas_, kEngineSppPerReplica, kReferenceSpp);
  if (HasFatalFailure()) return;

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
