// Agreement of the bake engine with the independent CPU reference
// (tests/reference) on a scene of glTF BRDF materials: the bundled Cornell
// box (open at the front, like the original) with its materials changed in
// code to GGX dielectrics of roughness 0.5 and 0.8 with coloured bases, the
// tall block a gold-like metal (metallic 1, roughness 0.4), the emissive
// ceiling light unchanged (a roughness-1 dielectric, shaded with the GGX
// layer like every material of a scene that needs one). 3 bounces.
//
// The reference evaluates the glTF 2.0 Appendix B BRDF with Kulla-Conty
// compensation from its own implementation (reference_bsdf.h: double
// precision, its own E(mu) quadrature, cosine / GGX mixture sampling, NEE
// only); the engine shares none of that code. The comparison is the one of
// reference_agreement_test (lightmap_agreement.h): Welch t per texel and
// channel with Šidák over the family, and a pooled luminance ratio. On top
// of it, a spatial check: the pooled ratio over texels near the room's
// edges (within kNearFraction of the box size of two walls) and over the
// rest, and the ratio of the two, each with its z; a model that is wrong at
// grazing angles (too dark in corners) shows there.
//
// Deliberate model errors, each a reference bake with a different
// BrdfModel, must be rejected by the same checks: the previous model's
// diffuse weight (1 - F(f0, n.v)) without compensation, and Appendix B
// without the compensation lobe.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "atlas/atlas.h"
#include "atlas/sample_info.h"
#include "atlas/texel_raster.h"
#include "bake/bake.h"
#include "device/context.h"
#include "lightmap_agreement.h"
#include "reference/cpu_lightmap_tracer.h"
#include "scene/gltf_import.h"
#include "support/device_context.h"

namespace luxel {
namespace {

using reference::BrdfModel;
using test::EngineBakes;
using test::Summary;

constexpr const char* kScene = LUXEL_SCENES_DIR "/cornell_box.gltf";
constexpr int kResolution = 64;
constexpr int kMaxBounces = 3;
constexpr int kReplicas = 16;
constexpr uint32_t kEngineSppPerReplica = 64;
constexpr uint32_t kReferenceSpp = 1024;
constexpr uint32_t kInjectedSpp = 2048;  // the references with a deliberate model error
constexpr double kNearFraction = 0.05;   // "near an edge": of the box size, from two walls

// The materials of the test scene; fails when the bundled scene changed.
std::string use_ggx_materials(scene::Scene* s) {
  auto find = [&](const char* name) {
    for (size_t m = 0; m < s->materials.size(); ++m)
      if (s->materials[m].name == name) return static_cast<int>(m);
    return -1;
  };
  const int white = find("White"), red = find("Red"), green = find("Green");
  if (white < 0 || red < 0 || green < 0) return "materials White/Red/Green not found";
  s->materials[static_cast<size_t>(white)].roughness_factor = 0.5f;
  s->materials[static_cast<size_t>(red)].roughness_factor = 0.5f;
  s->materials[static_cast<size_t>(green)].roughness_factor = 0.8f;
  for (int m : {white, red, green}) s->materials[static_cast<size_t>(m)].metallic_factor = 0.0f;
  scene::Material gold;
  gold.name = "Gold";
  gold.base_color_factor = {1.0f, 0.71f, 0.29f, 1.0f};
  gold.metallic_factor = 1.0f;
  gold.roughness_factor = 0.4f;
  s->materials.push_back(gold);
  const int gold_index = static_cast<int>(s->materials.size()) - 1;
  // The tall block: the white triangles reaching its top at y = 3.30 (the
  // short block ends at 1.65, the room spans 0 - 5.49).
  int moved = 0;
  for (scene::Mesh& mesh : s->meshes) {
    for (size_t t = 0; t < mesh.triangle_material.size(); ++t) {
      if (mesh.triangle_material[t] != white) continue;
      float top = -1e30f;
      for (int k = 0; k < 3; ++k) top = std::max(top, mesh.positions[mesh.indices[t * 3 + k]].y);
      if (top > 3.2f && top < 3.4f) {
        mesh.triangle_material[t] = gold_index;
        ++moved;
      }
    }
  }
  if (moved != 10) return strprintf("expected the tall block's 10 triangles, found %d", moved);
  return "";
}

// Mean world position of each covered texel's valid sample positions.
std::vector<Vec3> texel_points(const scene::Scene& s, const atlas::Atlas& a) {
  std::vector<Vec3> points(static_cast<size_t>(a.width) * static_cast<size_t>(a.height));
  auto info = atlas::build_sample_info(s, a);
  EXPECT_TRUE(info.is_ok()) << info.status().to_string();
  if (!info.is_ok()) return points;
  const atlas::SampleInfo& si = info.value();
  for (uint32_t texel : si.covered_texels) {
    const uint32_t off = si.offsets[texel];
    const uint32_t n =
        static_cast<uint32_t>(std::popcount(si.words[off]) + std::popcount(si.words[off + 1]));
    double sum[3] = {0, 0, 0};
    for (uint32_t rank = 0; rank < n; ++rank) {
      const atlas::SamplePoint sp = atlas::sample_point(si, texel, rank);
      const scene::Instance& inst = s.instances[sp.instance];
      const scene::Mesh& mesh = s.meshes[static_cast<size_t>(inst.mesh)];
      const Vec3 w = atlas::atlas_barycentrics(
          atlas::texel_triangle(s, a, sp.instance, sp.triangle), sp.x, sp.y);
      Vec3 p{0, 0, 0};
      for (int k = 0; k < 3; ++k)
        p = p + mesh.positions[mesh.indices[size_t{sp.triangle} * 3 + k]] * w[k];
      p = transform_point(inst.object_to_world, p);
      for (int c = 0; c < 3; ++c) sum[c] += p[c];
    }
    points[texel] = {static_cast<float>(sum[0] / n), static_cast<float>(sum[1] / n),
                     static_cast<float>(sum[2] / n)};
  }
  return points;
}

struct Bakes {
  EngineBakes engine;
  reference::ReferenceLightmap ref, ref_previous, ref_no_compensation;
  std::vector<size_t> tested, near_edges, interior;
  double box_size = 0;
};

// The checks of one engine-reference pair, printed.
struct Verdict {
  Summary all, near, interior;
  test::RatioOfRatios near_over_interior;
  bool rejected() const {
    const double critical = reference::two_sided_critical(test::kFamilyAlpha, INFINITY);
    return all.texel_test_fails() || all.pooled_test_fails() ||
           std::abs(near_over_interior.z) > critical;
  }
};

Verdict judge(const Bakes& b, const reference::ReferenceLightmap& ref, const char* title) {
  Verdict v;
  v.all = test::compare_bakes(b.engine, ref, 1.0, b.tested);
  v.near = test::compare_bakes(b.engine, ref, 1.0, b.near_edges);
  v.interior = test::compare_bakes(b.engine, ref, 1.0, b.interior);
  v.near_over_interior = test::ratio_of_ratios(v.near, v.interior);
  test::print_summary(title, b.engine, ref, v.all);
  std::printf("  near edges (%zu texels)              ratio %.5f +- %.5f (z %.2f), max |t| %.2f\n",
              v.near.tested, v.near.ratio, v.near.ratio_se, v.near.pooled_z, v.near.max_abs_t);
  std::printf("  interior (%zu texels)               ratio %.5f +- %.5f (z %.2f), max |t| %.2f\n",
              v.interior.tested, v.interior.ratio, v.interior.ratio_se, v.interior.pooled_z,
              v.interior.max_abs_t);
  std::printf("  near edges / interior               %.5f +- %.5f (z %.2f)\n",
              v.near_over_interior.ratio, v.near_over_interior.se, v.near_over_interior.z);
  return v;
}

class GgxReferenceAgreement : public testing::DeviceTest<> {
 protected:
  static void SetUpTestSuite() {
    auto scene = scene::import_gltf_file(kScene);
    if (!scene) return fail("import: " + scene.status().to_string());
    if (std::string why = use_ggx_materials(&scene.value()); !why.empty()) return fail(why);
    ASSERT_NO_FATAL_FAILURE(DeviceTest::SetUpTestSuite());
    auto bakes = std::make_unique<Bakes>();
    pipeline::BakeSettings settings;
    settings.atlas.resolution = kResolution;
    settings.samples_per_texel = kEngineSppPerReplica;
    settings.max_bounces = kMaxBounces;
    settings.filter = pipeline::Filter::kBox;
    settings.clamp_luminance = 0;  // unbiased
    settings.adaptive = false;     // every texel the same samples, as the reference's
    settings.intersector = accel::IntersectorKind::kEmbree;
    for (int r = 0; r < kReplicas; ++r) {
      settings.seed = 2000u + static_cast<uint32_t>(r);
      auto result = pipeline::bake(scene.value(), settings, *ctx_);
      if (!result)
        return fail(strprintf("engine bake (seed %u): ", settings.seed) +
                    result.status().to_string());
      bakes->engine.seconds += result.value().seconds;
      bakes->engine.paths += result.value().paths;
      bakes->engine.device = result.value().device + ", " + result.value().intersector;
      features_ = result.value().features;
      bakes->engine.replicas.push_back(std::move(result.value()));
    }

    auto atlas = atlas::build_atlas(scene.value(), settings.atlas);
    if (!atlas) return fail("atlas: " + atlas.status().to_string());
    atlas_ = std::make_unique<atlas::Atlas>(std::move(atlas.value()));
    reference::ReferenceSettings ref_settings;
    ref_settings.samples_per_texel = kReferenceSpp;
    ref_settings.max_bounces = kMaxBounces;
    ref_settings.seed = 17;
    ref_settings.threads = 2;
    for (auto [model, out] : {std::pair{BrdfModel::kGltf, &bakes->ref},
                              std::pair{BrdfModel::kPreviousDiffuseWeight, &bakes->ref_previous},
                              std::pair{BrdfModel::kNoCompensation, &bakes->ref_no_compensation}}) {
      ref_settings.brdf = model;
      ref_settings.samples_per_texel = model == BrdfModel::kGltf ? kReferenceSpp : kInjectedSpp;
      ++ref_settings.seed;
      auto ref = reference::bake_reference(scene.value(), *atlas_, ref_settings);
      if (!ref) return fail("reference: " + ref.status().to_string());
      *out = std::move(ref.value());
    }

    // Texels near the room's edges: within kNearFraction of the box size of
    // two of its walls (floor, ceiling, back, left, right; the front at
    // z = max is open). The box is the scene's bounding box.
    bakes->tested = test::fully_covered_texels(bakes->engine);
    const std::vector<Vec3> points = texel_points(scene.value(), *atlas_);
    Bounds3 box;
    for (const scene::Instance& inst : scene.value().instances)
      for (const Vec3& p : scene.value().meshes[static_cast<size_t>(inst.mesh)].positions)
        box.extend(transform_point(inst.object_to_world, p));
    bakes->box_size = std::max({box.hi.x - box.lo.x, box.hi.y - box.lo.y, box.hi.z - box.lo.z});
    const double d = kNearFraction * bakes->box_size;
    for (size_t t : bakes->tested) {
      const Vec3 p = points[t];
      const double dist[5] = {p.x - box.lo.x, box.hi.x - p.x, p.y - box.lo.y, box.hi.y - p.y,
                              p.z - box.lo.z};
      int walls = 0;
      for (double w : dist) walls += std::abs(w) < d ? 1 : 0;
      (walls >= 2 ? bakes->near_edges : bakes->interior).push_back(t);
    }
    bakes_ = std::move(bakes);
  }
  static void TearDownTestSuite() {
    bakes_.reset();
    atlas_.reset();
    DeviceTest::TearDownTestSuite();
  }
  static void fail(const std::string& why) { setup_error_ = why; }

  void SetUp() override {
    ASSERT_TRUE(bakes_ && bakes_->ref.width > 0) << "setup failed: " << setup_error_;
  }

  static std::unique_ptr<Bakes> bakes_;
  static std::unique_ptr<atlas::Atlas> atlas_;
  static std::string setup_error_, features_;
};

std::unique_ptr<Bakes> GgxReferenceAgreement::bakes_;
std::unique_ptr<atlas::Atlas> GgxReferenceAgreement::atlas_;
std::string GgxReferenceAgreement::setup_error_;
std::string GgxReferenceAgreement::features_;

TEST_F(GgxReferenceAgreement, EngineAgreesWithReferenceWithinConfidenceBounds) {
  const Bakes& b = *bakes_;
  test::expect_same_texel_domain(b.engine, b.ref, *atlas_, kEngineSppPerReplica, kReferenceSpp);
  if (HasFatalFailure()) return;
  // The engine compiled its GGX layer (the scene is not all rough dielectrics).
  EXPECT_NE(features_.find("specular"), std::string::npos) << features_;

  const Verdict v =
      judge(b, b.ref, "GGX Cornell box: engine (Embree) vs CPU reference (3 bounces)");
  std::printf("  box size %.3f, near = within %.3f of two walls\n", b.box_size,
              kNearFraction * b.box_size);
  // Not trivially passing: a lit lightmap, enough texels, errors small
  // enough that the per-texel test has teeth, and a real set of edge texels.
  EXPECT_GE(v.all.tested, 200u);
  EXPECT_GT(v.all.ref_mean_y, 0.05);
  EXPECT_GT(v.all.nonblack_fraction, 0.9);
  EXPECT_LT(v.all.median_rel_se, 0.05);
  EXPECT_GE(v.near.tested, 30u);
  EXPECT_LT(v.near_over_interior.se, 0.02);
  // The tests themselves.
  EXPECT_EQ(v.all.failures, 0u) << "worst texel " << v.all.worst_texel << " channel "
                                << v.all.worst_channel << ": |t| " << v.all.max_abs_t;
  EXPECT_FALSE(v.all.pooled_test_fails()) << "pooled ratio " << v.all.ratio << " +- "
                                          << v.all.ratio_se << " (z " << v.all.pooled_z << ")";
  EXPECT_FALSE(v.near.pooled_test_fails()) << "near edges: z " << v.near.pooled_z;
  EXPECT_FALSE(v.interior.pooled_test_fails()) << "interior: z " << v.interior.pooled_z;
  EXPECT_FALSE(v.rejected());
}

TEST_F(GgxReferenceAgreement, RejectsThePreviousDiffuseWeight) {
  const Bakes& b = *bakes_;
  const Verdict v = judge(b, b.ref_previous,
                          "Same engine bakes, reference with the previous model's diffuse weight "
                          "(1 - F(f0, n.v)), no compensation (deliberate error)");
  EXPECT_TRUE(v.rejected()) << "max |t| " << v.all.max_abs_t << ", pooled z " << v.all.pooled_z;
}

TEST_F(GgxReferenceAgreement, RejectsAMissingCompensationLobe) {
  const Bakes& b = *bakes_;
  const Verdict v = judge(b, b.ref_no_compensation,
                          "Same engine bakes, reference without the Kulla-Conty compensation lobe "
                          "(deliberate error)");
  EXPECT_TRUE(v.rejected()) << "max |t| " << v.all.max_abs_t << ", pooled z " << v.all.pooled_z;
}

}  // namespace
}  // namespace luxel
