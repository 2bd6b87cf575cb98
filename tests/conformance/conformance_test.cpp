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
#include <cstdlib>
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
float edge_distance(const cl::LuxHit& h) {
  return std::min({h.u, h.v, 1.0f - h.u - h.v});
}

// Distance tolerance: 1e-4 relative, plus a few ULPs of the coordinates
// involved divided by the cosine between ray and surface. Rays leaving a
// surface hit neighbouring geometry at t ~ 1e-5, often at grazing angles:
// there the position along the surface normal is accurate to a few ULPs of
// the coordinates, and the distance along the ray is that error / cos(theta).
float t_tolerance(const cl::LuxRay& r, float t, const TriangleSoup& soup, int prim) {
  const float mag = std::max({std::fabs(r.org_tmin.x), std::fabs(r.org_tmin.y),
                              std::fabs(r.org_tmin.z), std::fabs(r.org_tmin.x + r.dir_tmax.x * t),
                              std::fabs(r.org_tmin.y + r.dir_tmax.y * t),
                              std::fabs(r.org_tmin.z + r.dir_tmax.z * t), 1e-3f});
  const Vec3 d{r.dir_tmax.x, r.dir_tmax.y, r.dir_tmax.z};
  const Vec3 n =
      normalize(cross(soup.v(static_cast<size_t>(prim), 1) - soup.v(static_cast<size_t>(prim), 0),
                      soup.v(static_cast<size_t>(prim), 2) - soup.v(static_cast<size_t>(prim), 0)));
  const float len = length(d);
  const float cos_theta = std::max(std::fabs(dot(n, d)) / len, 1e-3f);
  return 1e-4f * t + 8.0f * mag * 0x1p-23f / (len * cos_theta);
}

struct Tally {
  size_t rays = 0, hits = 0;
  size_t mismatch = 0;      // hit vs miss, or different triangles at different distances
  size_t hit_miss = 0;      // of which: one tracer hit, the other missed
  size_t tie_edge = 0;      // different triangles, same distance, hit within 1e-3 of an edge
  size_t tie_coplanar = 0;  // different triangles, same distance, interior: coincident faces
  size_t far_t = 0;         // same triangle, distance beyond tolerance
  void add(const Tally& o) {
    rays += o.rays;
    hits += o.hits;
    mismatch += o.mismatch;
    hit_miss += o.hit_miss;
    tie_edge += o.tie_edge;
    tie_coplanar += o.tie_coplanar;
    far_t += o.far_t;
  }
};

TEST(Conformance, OpenClAgreesWithEmbree) {
  ASSERT_FALSE(g_scene.empty()) << "run with --scene=PATH";
  auto scene = scene::import_gltf_file(g_scene);
  ASSERT_TRUE(scene.is_ok()) << scene.status().to_string();
  auto soup = build_triangle_soup(scene.value());
  ASSERT_TRUE(soup.is_ok()) << soup.status().to_string();
  auto ctx = device::Context::create("");
  ASSERT_TRUE(ctx.is_ok()) << ctx.status().to_string();
  // The device's node layout (LUXEL_BVH_WIDTH=2|4 picks the other).
  BvhBuildOptions bvh_options;
  bvh_options.width = preferred_bvh_width(ctx.value()->info());
  auto bvh = build_bvh(soup.value(), bvh_options);
  ASSERT_TRUE(bvh.is_ok()) << bvh.status().to_string();
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
  const Set closest_sets[] = {
      {RayKind::kCoherent, 400000}, {RayKind::kIncoherent, 400000}, {RayKind::kRandom, 250000}};
  Tally total;
  for (const Set& set : closest_sets) {
    const auto rays = make_rays(soup.value(), set.kind, set.count, 2024);
    auto h = cl.value()->closest(rays);
    ASSERT_TRUE(h.is_ok()) << h.status().to_string();
    std::vector<cl::LuxHit> e(rays.size());
    embree.value()->intersect(rays, e, set.kind == RayKind::kCoherent);
    Tally t;
    t.rays = rays.size();
    const bool verbose = std::getenv("LUXEL_CONFORMANCE_VERBOSE") != nullptr;
    for (size_t i = 0; i < rays.size(); ++i) {
      const auto& a = h.value()[i];
      const auto& b = e[i];
      t.hits += b.prim >= 0;
      if (a.prim == b.prim) {
        if (a.prim >= 0 && std::fabs(a.t - b.t) > t_tolerance(rays[i], b.t, soup.value(), b.prim))
          ++t.far_t;
        continue;
      }
      const bool both_hit = a.prim >= 0 && b.prim >= 0;
      if (both_hit &&
          std::fabs(a.t - b.t) <= std::max(t_tolerance(rays[i], b.t, soup.value(), a.prim),
                                           t_tolerance(rays[i], b.t, soup.value(), b.prim))) {
        // An equidistant tie: both answers are correct.
        (std::min(edge_distance(a), edge_distance(b)) < 1e-3f ? t.tie_edge : t.tie_coplanar)++;
        continue;
      }
      if (verbose && t.mismatch < 8)
        std::printf(
            "    ray %zu: OpenCL prim %d t %.7g uv (%.4g %.4g) | Embree prim %d t %.7g uv (%.4g "
            "%.4g)\n",
            i, a.prim, a.t, a.u, a.v, b.prim, b.t, b.u, b.v);
      ++t.mismatch;
      t.hit_miss += !both_hit;
    }
    std::printf(
        "  closest %-10s %8zu rays, %5.1f%% hit: %zu mismatches (%zu hit-vs-miss); ties at equal "
        "distance: "
        "%zu at shared edges, %zu on coincident faces; %zu same-triangle distances beyond "
        "tolerance\n",
        ray_kind_name(set.kind), t.rays, 100.0 * t.hits / t.rays, t.mismatch, t.hit_miss,
        t.tie_edge, t.tie_coplanar, t.far_t);
    total.add(t);
  }
  // Agreement on hit/miss and triangle, where a tie at equal distance between
  // coincident or edge-sharing triangles counts as agreement.
  const double agreement = 1.0 - static_cast<double>(total.mismatch + total.far_t) / total.rays;
  std::printf("  closest total: %zu rays, agreement %.5f%%, %zu ties (%.3f%%)\n", total.rays,
              100.0 * agreement, total.tie_edge + total.tie_coplanar,
              100.0 * (total.tie_edge + total.tie_coplanar) / total.rays);
  EXPECT_GE(agreement, kRequiredAgreement)
      << total.mismatch << " mismatches of " << total.rays << " rays";
  EXPECT_LE(total.far_t, total.rays / 10000)
      << "hits on the same triangle at distances beyond 1e-4 relative";
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
