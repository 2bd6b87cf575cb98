// Conformance: the OpenCL closest-hit and any-hit kernels against Embree on
// the same rays over a real scene (RadeonRays' conformance test, run against
// Embree instead of brute force).
//
// At least 1M rays per scene, mixed: coherent cube-map camera rays,
// incoherent surface-bounce rays and random rays through the scene bounds.
// Required: hit/miss and triangle agree on >= 99.99 % of rays, distances of
// agreeing hits within 1e-4 relative, any-hit agrees on >= 99.99 %.
// Disagreements are reported, classified by whether the hit lies within a
// tiny distance of a triangle edge (ties between the two triangles sharing an
// edge are resolved differently by the two watertight tests; expected).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "accel/bvh_builder.h"
#include "accel/cl_tracer.h"
#include "accel/embree_tracer.h"
#include "accel/ray_gen.h"
#include "accel/triangle_soup.h"
#include "device/context.h"
#include "scene/gltf_import.h"

namespace luxel::accel {
namespace {

std::string g_scene;

constexpr double kRequiredAgreement = 0.9999;

// Smallest barycentric coordinate of a hit (distance to the nearest edge, in
// barycentric units).
float edge_distance(const cl::LuxHit& h) { return std::min({h.u, h.v, 1.0f - h.u - h.v}); }

struct Tally {
  size_t rays = 0, disagree = 0, disagree_at_edge = 0, hit_miss = 0, far_t = 0, hits = 0;
};

TEST(Conformance, OpenClAgreesWithEmbree) {
  ASSERT_FALSE(g_scene.empty()) << "run with --scene=PATH";
  auto scene = scene::import_gltf_file(g_scene);
  ASSERT_TRUE(scene.is_ok()) << scene.status().to_string();
  auto soup = build_triangle_soup(scene.value());
  ASSERT_TRUE(soup.is_ok()) << soup.status().to_string();
  auto bvh = build_bvh(soup.value());
  ASSERT_TRUE(bvh.is_ok()) << bvh.status().to_string();
  auto ctx = device::Context::create("");
  ASSERT_TRUE(ctx.is_ok()) << ctx.status().to_string();
  auto cl = ClTracer::create(*ctx.value(), bvh.value());
  ASSERT_TRUE(cl.is_ok()) << cl.status().to_string();
  auto embree = EmbreeTracer::create(bvh.value());
  ASSERT_TRUE(embree.is_ok()) << embree.status().to_string();
  std::printf("scene %s: %zu triangles, BVH %zu nodes depth %u, features: %s, device: %s\n",
              g_scene.c_str(), soup->size(), bvh->stats.nodes, bvh->stats.max_depth,
              cl.value()->features().describe().c_str(), ctx.value()->info().device_name.c_str());

  struct Set {
    RayKind kind;
    size_t count;
  };
  const Set closest_sets[] = {{RayKind::kCoherent, 400000}, {RayKind::kIncoherent, 400000}, {RayKind::kRandom, 250000}};
  Tally total;
  for (const Set& set : closest_sets) {
    const auto rays = make_rays(soup.value(), set.kind, set.count, 2024);
    auto h = cl.value()->closest(rays);
    ASSERT_TRUE(h.is_ok()) << h.status().to_string();
    std::vector<cl::LuxHit> e(rays.size());
    embree.value()->intersect(rays, e, set.kind == RayKind::kCoherent);
    Tally t;
    t.rays = rays.size();
    for (size_t i = 0; i < rays.size(); ++i) {
      const auto& a = h.value()[i];
      const auto& b = e[i];
      t.hits += b.prim >= 0;
      if (a.prim != b.prim) {
        ++t.disagree;
        if ((a.prim < 0) != (b.prim < 0)) ++t.hit_miss;
        const float edge = std::min(a.prim >= 0 ? edge_distance(a) : 1.0f, b.prim >= 0 ? edge_distance(b) : 1.0f);
        // Different triangles at the same distance: a shared edge or vertex,
        // or coplanar overlapping faces (both answers are correct).
        const bool same_t = a.prim >= 0 && b.prim >= 0 && std::fabs(a.t - b.t) <= 1e-4f * std::max(1.0f, b.t);
        if (edge < 1e-3f || same_t) ++t.disagree_at_edge;
      } else if (a.prim >= 0 && std::fabs(a.t - b.t) > 1e-4f * std::max(1e-3f, b.t)) {
        ++t.far_t;
      }
    }
    std::printf("  closest %-10s %8zu rays, %5.1f%% hit: %zu disagree (%zu at shared edges/coplanar, %zu hit-vs-miss), %zu distance > 1e-4 rel\n",
                ray_kind_name(set.kind), t.rays, 100.0 * t.hits / t.rays, t.disagree, t.disagree_at_edge,
                t.hit_miss, t.far_t);
    total.rays += t.rays;
    total.disagree += t.disagree;
    total.far_t += t.far_t;
    total.disagree_at_edge += t.disagree_at_edge;
  }
  const double agreement = 1.0 - static_cast<double>(total.disagree) / total.rays;
  EXPECT_GE(agreement, kRequiredAgreement) << total.disagree << " of " << total.rays << " rays disagree";
  EXPECT_LE(total.far_t, total.rays / 10000) << "hits on the same triangle at different distances";
  EXPECT_GE(total.rays, 1000000u);

  // Any-hit: shadow segments plus the incoherent rays (unbounded).
  size_t any_rays = 0, any_disagree = 0;
  for (RayKind kind : {RayKind::kShadow, RayKind::kIncoherent}) {
    const auto rays = make_rays(soup.value(), kind, 250000, 77);
    auto o = cl.value()->any(rays);
    ASSERT_TRUE(o.is_ok()) << o.status().to_string();
    std::vector<int> e(rays.size());
    embree.value()->occluded(rays, e);
    size_t d = 0, occluded = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      d += o.value()[i] != e[i];
      occluded += e[i];
    }
    std::printf("  any     %-10s %8zu rays, %5.1f%% occluded: %zu disagree\n", ray_kind_name(kind),
                rays.size(), 100.0 * occluded / rays.size(), d);
    any_rays += rays.size();
    any_disagree += d;
  }
  EXPECT_GE(1.0 - static_cast<double>(any_disagree) / any_rays, kRequiredAgreement);
}

}  // namespace
}  // namespace luxel::accel

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a.rfind("--scene=", 0) == 0) luxel::accel::g_scene = a.substr(8);
  }
  return RUN_ALL_TESTS();
}
