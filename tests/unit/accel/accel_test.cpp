// BVH build, OpenCL traversal and the Embree tracer on hand-made scenes with
// known answers (no file import involved).
// Over 500 lines: the hand-made scenes serve the BVH builder, both traversal
// layouts and the Embree tracer alike.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <numeric>
#include <random>

#include "accel/bvh_builder.h"
#include "accel/cl_tracer.h"
#include "accel/embree_intersector.h"
#include "accel/embree_tracer.h"
#include "accel/ray_gen.h"
#include "accel/triangle_soup.h"
#include "device/context.h"
#include "kernels/shared/ray_offset.h"
#include "support/device_context.h"

namespace luxel::accel {
namespace {

using cl::LuxHit;
using cl::LuxRay;

// A scene with one mesh per call to add_mesh and one instance per transform.
struct SceneBuilder {
  scene::Scene s;
  SceneBuilder() { s.materials.push_back(scene::Material{}); }
  int add_mesh(std::vector<Vec3> p, std::vector<uint32_t> idx, std::vector<Vec2> uv0 = {},
               int material = 0) {
    scene::Mesh m;
    m.name = "m" + std::to_string(s.meshes.size());
    m.positions = std::move(p);
    m.normals.assign(m.positions.size(), Vec3{0, 0, 1});
    m.uv0 = uv0.empty() ? std::vector<Vec2>(m.positions.size()) : std::move(uv0);
    m.uv1 = m.uv0;
    m.indices = std::move(idx);
    m.triangle_material.assign(m.indices.size() / 3, material);
    s.meshes.push_back(std::move(m));
    return static_cast<int>(s.meshes.size()) - 1;
  }
  void instance(int mesh, Mat4 xf = {}) {
    scene::Instance i;
    i.name = "i" + std::to_string(s.instances.size());
    i.mesh = mesh;
    i.object_to_world = xf;
    s.instances.push_back(i);
  }
};

// An n x n grid of quads (2 triangles each) on z = 0 spanning [0, size]^2.
void add_grid(SceneBuilder& b, int n, float size, Mat4 xf = {}) {
  std::vector<Vec3> p;
  std::vector<Vec2> uv;
  std::vector<uint32_t> idx;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) {
      p.push_back({size * x / n, size * y / n, 0});
      uv.push_back({static_cast<float>(x) / n, static_cast<float>(y) / n});
    }
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const uint32_t a = y * (n + 1) + x, b2 = a + 1, c = a + (n + 1), d = c + 1;
      idx.insert(idx.end(), {a, b2, d, a, d, c});
    }
  b.instance(b.add_mesh(p, idx, uv), xf);
}

Mat4 translate(double x, double y, double z) {
  Mat4 m;
  m.at(0, 3) = x;
  m.at(1, 3) = y;
  m.at(2, 3) = z;
  return m;
}

LuxRay ray(Vec3 o, Vec3 d, float tmin = 0, float tmax = INFINITY) {
  return {{o.x, o.y, o.z, tmin}, {d.x, d.y, d.z, tmax}};
}

// Every test runs for both OpenCL node layouts (BVH2 and BVH4).
class AccelTest : public testing::DeviceTest<::testing::TestWithParam<unsigned>> {
 protected:
  // Builds soup, BVH and both tracers for the scene.
  void build(const scene::Scene& s, BvhBuildOptions opt = {}) {
    auto soup = build_triangle_soup(s);
    ASSERT_TRUE(soup.is_ok()) << soup.status().to_string();
    soup_ = std::move(soup.value());
    opt.width = GetParam();
    auto bvh = build_bvh(soup_, opt);
    ASSERT_TRUE(bvh.is_ok()) << bvh.status().to_string();
    bvh_ = std::move(bvh.value());
    ASSERT_EQ(bvh_.width, GetParam());
    auto cl = ClTracer::create(*ctx_, bvh_);
    ASSERT_TRUE(cl.is_ok()) << cl.status().to_string();
    EXPECT_EQ(cl.value()->features().has(device::Feature::BVH4), GetParam() == 4);
    cl_ = std::move(cl.value());
    auto em = EmbreeTracer::create(bvh_);
    ASSERT_TRUE(em.is_ok()) << em.status().to_string();
    embree_ = std::move(em.value());
  }
  std::vector<LuxHit> cl_closest(const std::vector<LuxRay>& rays) {
    auto h = cl_->closest(rays);
    EXPECT_TRUE(h.is_ok()) << h.status().to_string();
    return h.is_ok() ? h.value() : std::vector<LuxHit>(rays.size());
  }
  std::vector<LuxHit> embree_closest(const std::vector<LuxRay>& rays) {
    std::vector<LuxHit> h(rays.size());
    embree_->intersect(rays, h);
    return h;
  }

  TriangleSoup soup_;
  DeviceBvh bvh_;
  std::unique_ptr<ClTracer> cl_;
  std::unique_ptr<EmbreeTracer> embree_;
};

TEST_P(AccelTest, SingleTriangleDistanceAndBarycentrics) {
  SceneBuilder b;
  b.instance(b.add_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {0, 1, 2}));
  build(b.s);
  EXPECT_EQ(bvh_.stats.triangles, 1u);
  const std::vector<LuxRay> rays = {
      ray({0.25f, 0.5f, 2}, {0, 0, -1}),              // hit at t = 2
      ray({0.25f, 0.5f, -3}, {0, 0, 2}),              // back face, t = 1.5 (dir not unit)
      ray({0.75f, 0.75f, 2}, {0, 0, -1}),             // outside the triangle
      ray({0.25f, 0.5f, 2}, {0, 0, -1}, 0.0f, 1.5f),  // tmax before the triangle
      ray({0.25f, 0.5f, 2}, {0, 0, -1}, 2.5f),        // tmin after the triangle
      ray({0.25f, 0.5f, 2}, {0, 0, 1}),               // pointing away
  };
  const auto h = cl_closest(rays);
  ASSERT_EQ(h.size(), rays.size());
  EXPECT_EQ(h[0].prim, 0);
  EXPECT_FLOAT_EQ(h[0].t, 2.0f);
  EXPECT_NEAR(h[0].u, 0.25f, 1e-6f);
  EXPECT_NEAR(h[0].v, 0.5f, 1e-6f);
  EXPECT_EQ(h[1].prim, 0);
  EXPECT_FLOAT_EQ(h[1].t, 1.5f);
  for (int i = 2; i < 6; ++i) EXPECT_EQ(h[static_cast<size_t>(i)].prim, -1) << "ray " << i;
  const auto e = embree_closest(rays);
  for (size_t i = 0; i < rays.size(); ++i) {
    EXPECT_EQ(e[i].prim, h[i].prim) << "ray " << i;
    if (h[i].prim >= 0) EXPECT_FLOAT_EQ(e[i].t, h[i].t);
  }
  auto any = cl_->any(rays);
  ASSERT_TRUE(any.is_ok());
  EXPECT_EQ(any.value(), (std::vector<int>{1, 1, 0, 0, 0, 0}));
}

TEST_P(AccelTest, EmptySceneMissesEverything) {
  SceneBuilder b;
  build(b.s);
  const auto rays = make_rays(soup_, RayKind::kRandom, 1000, 3);
  for (const auto& h : cl_closest(rays)) EXPECT_EQ(h.prim, -1);
  auto any = cl_->any(rays);
  ASSERT_TRUE(any.is_ok());
  for (int o : any.value()) EXPECT_EQ(o, 0);
}

TEST_P(AccelTest, ClosestOfOverlappingLayersAndOriginalIds) {
  // Three parallel grids; rays from above hit the top one, from below the
  // bottom one. Original ids identify which instance was hit.
  SceneBuilder b;
  for (int k = 0; k < 3; ++k) add_grid(b, 8, 4.0f, translate(0, 0, k));
  build(b.s);
  const size_t per_grid = 8 * 8 * 2;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.01f, 3.99f);
  std::vector<LuxRay> rays;
  for (int i = 0; i < 2000; ++i)
    rays.push_back(ray({u(rng), u(rng), i % 2 ? 5.0f : -5.0f}, {0, 0, i % 2 ? -1.0f : 1.0f}));
  const auto h = cl_closest(rays);
  for (size_t i = 0; i < rays.size(); ++i) {
    ASSERT_GE(h[i].prim, 0);
    const size_t inst = soup_.instance[static_cast<size_t>(h[i].prim)];
    EXPECT_EQ(inst, i % 2 ? 2u : 0u);
    EXPECT_NEAR(h[i].t, i % 2 ? 3.0f : 5.0f, 1e-5f);
  }
  EXPECT_EQ(soup_.size(), 3 * per_grid);
}

TEST_P(AccelTest, WatertightAtSharedEdgesAndVertices) {
  // Rays aimed exactly at grid edges and vertices must never slip through.
  SceneBuilder b;
  add_grid(b, 16, 16.0f);
  build(b.s);
  std::vector<LuxRay> rays;
  for (int y = 1; y < 16; ++y)
    for (int x = 1; x < 16; ++x) {
      rays.push_back(ray({float(x), float(y), 3}, {0, 0, -1}));  // vertex
      rays.push_back(ray({x + 0.5f, float(y), 3}, {0, 0, -1}));  // horizontal edge
      rays.push_back(ray({x + 0.5f, y + 0.5f, 3}, {0, 0, -1}));  // diagonal edge
      rays.push_back(
          ray({float(x) - 3, float(y) - 2, 3}, {1, 2 / 3.0f, -1}));  // slanted to a vertex
    }
  const auto h = cl_closest(rays);
  size_t misses = 0;
  for (const auto& hit : h) misses += hit.prim < 0;
  EXPECT_EQ(misses, 0u);
  auto any = cl_->any(rays);
  ASSERT_TRUE(any.is_ok());
  for (int o : any.value()) EXPECT_EQ(o, 1);
}

TEST_P(AccelTest, OffsetRaysDoNotSelfIntersectAtLargeCoordinates) {
  // A tilted grid far from the origin; secondary rays leave from hit points
  // offset with the shared ray_offset.h and must not hit their own surface.
  for (double far : {0.0, 1e3, 1e5}) {
    SceneBuilder b;
    Mat4 xf = translate(far, far * 0.5, -far);
    const double c = std::cos(0.3), s = std::sin(0.3);
    xf.at(1, 1) = c;
    xf.at(1, 2) = -s;
    xf.at(2, 1) = s;
    xf.at(2, 2) = c;
    add_grid(b, 32, 64.0f, xf);
    build(b.s);
    const Vec3 n = normalize(transform_normal(xf, {0, 0, 1}));
    // Primary rays straight down onto the interior of the surface.
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> g(1.0f, 63.0f);
    std::vector<LuxRay> primary;
    for (int i = 0; i < 4000; ++i) {
      const Vec3 p = transform_point(xf, {g(rng), g(rng), 0});
      primary.push_back(ray(p + n * 10.0f, n * -1.0f));
    }
    const auto h = cl_closest(primary);
    std::vector<LuxRay> secondary;
    for (size_t i = 0; i < h.size(); ++i) {
      ASSERT_GE(h[i].prim, 0) << "far=" << far;
      // The hit point from barycentrics (as the bake pipeline does), not from
      // o + t d, whose error grows with the ray length.
      const size_t tri = static_cast<size_t>(h[i].prim);
      const float w = 1.0f - h[i].u - h[i].v;
      Vec3 p = soup_.v(tri, 0) * w + soup_.v(tri, 1) * h[i].u + soup_.v(tri, 2) * h[i].v;
      LUX_OFFSET_RAY_ORIGIN(p.x, p.y, p.z, n.x, n.y, n.z);
      // Grazing directions are the hard case.
      const Vec3 t = normalize(cross(n, {0.3f, 1, 0.2f}));
      secondary.push_back(ray(p, normalize(t + n * 0.01f)));
    }
    size_t self_hits = 0;
    for (const auto& s2 : cl_closest(secondary)) self_hits += s2.prim >= 0;
    EXPECT_EQ(self_hits, 0u) << "far=" << far;
    size_t embree_self = 0;
    for (const auto& s2 : embree_closest(secondary)) embree_self += s2.prim >= 0;
    EXPECT_EQ(embree_self, 0u) << "far=" << far;
  }
}

TEST_P(AccelTest, AlphaMaskCutsOutAndMatchesEmbree) {
  // A quad whose texture is transparent on the left half (u < 0.5).
  SceneBuilder b;
  scene::Texture tex;
  tex.width = 4;
  tex.height = 1;
  tex.rgba8 = {255, 255, 255, 0, 255, 255, 255, 51, 255, 255, 255, 255, 255, 255, 255, 230};
  b.s.textures.push_back(tex);
  scene::Material m;
  m.alpha_mode = scene::AlphaMode::kMask;
  m.alpha_cutoff = 0.5f;
  m.base_color_texture.texture = 0;
  b.s.materials.push_back(m);
  const int mesh = b.add_mesh({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {0, 1, 2, 0, 2, 3},
                              {{0, 0}, {1, 0}, {1, 1}, {0, 1}}, 1);
  b.instance(mesh);
  // An opaque floor below catches what passes.
  add_grid(b, 1, 1.0f, translate(0, 0, -1));
  build(b.s);
  ASSERT_TRUE(cl_->features().has(device::Feature::ALPHA_MASK));
  std::vector<LuxRay> rays;
  for (int i = 0; i < 200; ++i) {
    const float x = 0.0025f + 0.005f * i;
    rays.push_back(ray({x, 0.5f, 1}, {0, 0, -1}));
  }
  const auto h = cl_closest(rays);
  const auto e = embree_closest(rays);
  for (size_t i = 0; i < rays.size(); ++i) {
    const float x = rays[i].org_tmin.x;
    const bool opaque = x >= 0.5f;
    ASSERT_GE(h[i].prim, 0);
    EXPECT_NEAR(h[i].t, opaque ? 1.0f : 2.0f, 1e-5f) << "x=" << x;
    EXPECT_EQ(h[i].prim, e[i].prim) << "x=" << x;
  }
  // Occlusion honours the mask too: rays that end above the floor.
  for (auto& r : rays) r.dir_tmax.w = 1.5f;
  auto any = cl_->any(rays);
  ASSERT_TRUE(any.is_ok());
  std::vector<int> em(rays.size());
  embree_->occluded(rays, em);
  for (size_t i = 0; i < rays.size(); ++i) {
    EXPECT_EQ(any.value()[i], rays[i].org_tmin.x >= 0.5f ? 1 : 0);
    EXPECT_EQ(any.value()[i], em[i]);
  }
}

TEST_P(AccelTest, OpaqueScenesCompileWithoutAlphaCode) {
  SceneBuilder b;
  add_grid(b, 2, 1.0f);
  build(b.s);
  EXPECT_FALSE(cl_->features().has(device::Feature::ALPHA_MASK));
  EXPECT_TRUE(bvh_.uvs.empty());
}

TEST_P(AccelTest, RandomRaysAgreeWithEmbreeOnAClutteredScene) {
  // Many randomly placed and rotated small grids: deep BVH, overlapping boxes.
  SceneBuilder b;
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-20, 20), a(0, 6.28);
  for (int i = 0; i < 300; ++i) {
    Mat4 xf = translate(u(rng), u(rng), u(rng));
    const double c = std::cos(a(rng)), s = std::sin(a(rng));
    xf.at(0, 0) = c;
    xf.at(0, 2) = s;
    xf.at(2, 0) = -s;
    xf.at(2, 2) = c;
    add_grid(b, 3, 2.0f, xf);
  }
  build(b.s, BvhBuildOptions{.max_leaf_size = 2});
  EXPECT_GT(bvh_.stats.max_depth, GetParam() == 2 ? 8u : 4u);
  for (RayKind kind : {RayKind::kRandom, RayKind::kIncoherent, RayKind::kCoherent}) {
    const auto rays = make_rays(soup_, kind, 20000, 17);
    const auto h = cl_closest(rays);
    const auto e = embree_closest(rays);
    size_t disagree = 0, hits = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      hits += h[i].prim >= 0;
      if (h[i].prim != e[i].prim)
        ++disagree;
      else if (h[i].prim >= 0)
        EXPECT_NEAR(h[i].t, e[i].t, 1e-4f * std::max(1.0f, e[i].t));
    }
    EXPECT_LE(disagree, rays.size() / 10000) << ray_kind_name(kind);
    EXPECT_GT(hits, rays.size() / 20) << ray_kind_name(kind);
  }
}

// The wavefront's indexed queries through both backends of accel::Intersector
// on device buffers: a shuffled active list with octant tags above the slot
// mask, a live count below the list's length, empty-interval "no shadow"
// rays. Results land at the source slots; slots not in the list keep what
// they held.
TEST_P(AccelTest, IndexedQueriesAgreeAcrossBackends) {
  SceneBuilder b;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-10, 10);
  for (int i = 0; i < 80; ++i) add_grid(b, 3, 2.0f, translate(u(rng), u(rng), u(rng)));
  build(b.s);
  auto rays = make_rays(soup_, RayKind::kIncoherent, 6000, 23);
  for (size_t i = 0; i < rays.size(); i += 7) rays[i].dir_tmax.w = -1.0f;  // empty interval
  for (size_t i = 3; i < rays.size(); i += 11) rays[i].dir_tmax.w = 2.0f;  // short shadow rays
  constexpr uint32_t kMask = 0x1FFFFFFFu;
  std::vector<uint32_t> list(rays.size());
  std::iota(list.begin(), list.end(), 0u);
  std::shuffle(list.begin(), list.end(), rng);
  for (size_t i = 0; i < list.size(); ++i) list[i] |= static_cast<uint32_t>(i % 8) << 29;
  const int live = static_cast<int>(rays.size() * 3 / 4);

  auto up = [&](const auto& v, const char* name) {
    auto r = ctx_->upload(v, name, CL_MEM_READ_WRITE);
    EXPECT_TRUE(r.is_ok()) << r.status().to_string();
    return std::move(r.value());
  };
  const LuxHit sentinel{-7.0f, 0.0f, 0.0f, -99};
  struct Out {
    std::vector<LuxHit> hits;
    std::vector<int> occluded;
  };
  auto run = [&](IntersectorKind kind) {
    auto x = make_intersector(kind, *ctx_, bvh_);
    EXPECT_TRUE(x.is_ok()) << x.status().to_string();
    EXPECT_EQ(x.value()->kind(), kind);
    auto r = up(rays, "rays");
    auto l = up(list, "list");
    auto n = up(std::vector<int>{live}, "count");
    auto h = up(std::vector<LuxHit>(rays.size(), sentinel), "hits");
    auto o = up(std::vector<int>(rays.size(), -5), "occluded");
    EXPECT_TRUE(x.value()->closest_indexed(r, l, n, kMask, h, list.size()).is_ok());
    EXPECT_TRUE(x.value()->any_indexed(r, l, n, kMask, o, list.size()).is_ok());
    Out out{std::vector<LuxHit>(rays.size()), std::vector<int>(rays.size())};
    EXPECT_TRUE(ctx_->read(h, out.hits).is_ok());
    EXPECT_TRUE(ctx_->read(o, out.occluded).is_ok());
    EXPECT_TRUE(ctx_->finish().is_ok());
    return out;
  };
  const Out e = run(IntersectorKind::kEmbree);
  const Out c = run(IntersectorKind::kOpenCl);
  std::vector<char> listed(rays.size(), 0);
  for (int i = 0; i < live; ++i) listed[list[static_cast<size_t>(i)] & kMask] = 1;
  size_t disagree = 0, hits = 0, blocked = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    if (!listed[i]) {
      EXPECT_EQ(e.hits[i].prim, -99) << "slot " << i << " not in the list was written";
      EXPECT_EQ(e.occluded[i], -5) << "slot " << i;
      EXPECT_EQ(c.occluded[i], -5) << "slot " << i;
      continue;
    }
    const bool empty = !(rays[i].dir_tmax.w > rays[i].org_tmin.w);
    if (empty) {
      EXPECT_EQ(e.occluded[i], 0) << "an empty interval is no shadow ray (slot " << i << ")";
      EXPECT_EQ(c.occluded[i], 0) << "slot " << i;
      EXPECT_LT(e.hits[i].prim, 0) << "slot " << i;
      continue;
    }
    hits += e.hits[i].prim >= 0;
    blocked += e.occluded[i] == 1;
    if (e.hits[i].prim != c.hits[i].prim || e.occluded[i] != c.occluded[i])
      ++disagree;
    else if (e.hits[i].prim >= 0)
      EXPECT_NEAR(e.hits[i].t, c.hits[i].t, 1e-4f * std::max(1.0f, c.hits[i].t)) << "slot " << i;
  }
  EXPECT_LE(disagree, rays.size() / 1000);
  EXPECT_GT(hits, rays.size() / 20);
  EXPECT_GT(blocked, rays.size() / 20);
}

TEST_P(AccelTest, BvhStatsAreConsistent) {
  SceneBuilder b;
  add_grid(b, 20, 10.0f);
  build(b.s, BvhBuildOptions{.max_leaf_size = 4});
  EXPECT_EQ(bvh_.stats.triangles, 800u);
  EXPECT_EQ(bvh_.triangles.size(), 800u);
  if (GetParam() == 2) {
    // A binary tree: leaves = inner nodes + 1 (no absent children here).
    EXPECT_EQ(bvh_.stats.leaves, bvh_.stats.nodes + 1);
    EXPECT_EQ(bvh_.nodes.size(), bvh_.stats.nodes);
    EXPECT_TRUE(bvh_.nodes4.empty());
  } else {
    // Every node has 2 to 4 children: leaves + inner nodes - 1 child slots.
    EXPECT_GE(bvh_.stats.leaves + bvh_.stats.nodes - 1, 2 * bvh_.stats.nodes);
    EXPECT_LE(bvh_.stats.leaves + bvh_.stats.nodes - 1, 4 * bvh_.stats.nodes);
    EXPECT_EQ(bvh_.nodes4.size(), bvh_.stats.nodes);
    EXPECT_TRUE(bvh_.nodes.empty());
  }
  EXPECT_GT(bvh_.stats.sah_cost, 0.0);
  // Every soup triangle appears exactly once in leaf order.
  std::vector<int> seen(800, 0);
  for (const auto& t : bvh_.triangles) seen[static_cast<size_t>(cl::as_int(t.v0.w))]++;
  for (int s : seen) EXPECT_EQ(s, 1);
}

// Isolated triangles along x, one leaf each: nodes with two, three and four
// children and absent slots. Each ray aims at one triangle's centroid from
// above or below, so a slot whose bounds, child index or leaf range is
// mixed up with another's returns the wrong triangle or a miss.
TEST_P(AccelTest, EveryTriangleOfSparseClustersIsFound) {
  for (int n : {1, 2, 3, 5, 6, 7, 9, 17, 33}) {
    SceneBuilder b;
    std::vector<Vec3> p;
    std::vector<uint32_t> idx;
    for (int i = 0; i < n; ++i) {
      // Uneven gaps so the SAH splits are not all balanced.
      const float x = 3.0f * i + 0.7f * static_cast<float>((i * 7) % 5);
      const auto base = static_cast<uint32_t>(p.size());
      p.insert(p.end(), {{x, 0, 0.1f * i}, {x + 1, 0, 0.1f * i}, {x, 1, 0.1f * i}});
      idx.insert(idx.end(), {base, base + 1, base + 2});
    }
    b.instance(b.add_mesh(p, idx));
    build(b.s, BvhBuildOptions{.max_leaf_size = 1});
    std::vector<LuxRay> rays;
    for (int i = 0; i < n; ++i) {
      const Vec3 c = (p[3 * i] + p[3 * i + 1] + p[3 * i + 2]) * (1.0f / 3.0f);
      rays.push_back(ray({c.x, c.y, c.z + 5}, {0, 0, -1}));
      rays.push_back(ray({c.x, c.y, c.z - 5}, {0, 0, 1}));
      rays.push_back(ray({c.x + 0.5f, c.y + 2, c.z}, {0, 0, -1}));  // beside it: a miss
    }
    const auto h = cl_closest(rays);
    auto any = cl_->any(rays);
    ASSERT_TRUE(any.is_ok());
    for (int i = 0; i < n; ++i) {
      const size_t r = 3 * static_cast<size_t>(i);
      EXPECT_EQ(h[r].prim, i) << "n=" << n;
      EXPECT_EQ(h[r + 1].prim, i) << "n=" << n;
      EXPECT_EQ(h[r + 2].prim, -1) << "n=" << n;
      EXPECT_NEAR(h[r].t, 5.0f, 1e-5f);
      EXPECT_EQ(any.value()[r], 1);
      EXPECT_EQ(any.value()[r + 2], 0);
    }
  }
}

// Structural check of the device layout: every node is reached once from the
// root, every slot's box contains what it references, leaves cover every
// triangle exactly once, absent slots are the documented empty encoding.
TEST_P(AccelTest, NodeLayoutIsATreeWithContainingBounds) {
  SceneBuilder b;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-20, 20);
  for (int i = 0; i < 120; ++i) add_grid(b, 2, 1.5f, translate(u(rng), u(rng), u(rng)));
  build(b.s, BvhBuildOptions{.max_leaf_size = 3});
  struct Box {
    float lo[3], hi[3];
  };
  std::vector<int> node_seen(bvh_.stats.nodes, 0), tri_seen(bvh_.triangles.size(), 0);
  auto contains = [](const Box& b, float x, float y, float z) {
    return x >= b.lo[0] && x <= b.hi[0] && y >= b.lo[1] && y <= b.hi[1] && z >= b.lo[2] &&
           z <= b.hi[2];
  };
  auto check_leaf = [&](const Box& box, int first, int count) {
    ASSERT_GT(count, 0);
    ASSERT_LE(static_cast<size_t>(first + count), bvh_.triangles.size());
    for (int t = first; t < first + count; ++t) {
      tri_seen[static_cast<size_t>(t)]++;
      for (const auto& v : {bvh_.triangles[t].v0, bvh_.triangles[t].v1, bvh_.triangles[t].v2})
        EXPECT_TRUE(contains(box, v.x, v.y, v.z)) << "triangle " << t;
    }
  };
  // Walks node `index`; `parent` is the box the parent holds for it.
  std::function<void(int, const Box&)> walk = [&](int index, const Box& parent) {
    ASSERT_GE(index, 0);
    ASSERT_LT(static_cast<size_t>(index), node_seen.size());
    node_seen[static_cast<size_t>(index)]++;
    if (GetParam() == 4) {
      const auto& n = bvh_.nodes4[static_cast<size_t>(index)];
      const float* lo[3] = {&n.lo_x.x, &n.lo_y.x, &n.lo_z.x};
      const float* hi[3] = {&n.hi_x.x, &n.hi_y.x, &n.hi_z.x};
      const int* child = &n.child.x;
      const int* count = &n.count.x;
      int present = 0;
      for (int s = 0; s < 4; ++s) {
        Box box;
        for (int k = 0; k < 3; ++k) {
          box.lo[k] = lo[k][s];
          box.hi[k] = hi[k][s];
        }
        if (child[s] < 0) {
          EXPECT_EQ(count[s], 0);
          for (int k = 0; k < 3; ++k) EXPECT_TRUE(std::isinf(box.lo[k]) && box.lo[k] > 0);
          continue;
        }
        ++present;
        for (int k = 0; k < 3; ++k) {
          EXPECT_GE(box.lo[k], parent.lo[k]);
          EXPECT_LE(box.hi[k], parent.hi[k]);
        }
        if (count[s] > 0)
          check_leaf(box, child[s], count[s]);
        else
          walk(child[s], box);
      }
      EXPECT_GE(present, index == 0 ? 1 : 2);
    } else {
      const auto& n = bvh_.nodes[static_cast<size_t>(index)];
      for (const auto* c : {&n.lmin, &n.rmin}) {
        const auto& mn = *c;
        const auto& mx = c == &n.lmin ? n.lmax : n.rmax;
        const int ref = cl::as_int(mn.w), count = cl::as_int(mx.w);
        if (ref < 0) continue;
        const Box box{{mn.x, mn.y, mn.z}, {mx.x, mx.y, mx.z}};
        for (int k = 0; k < 3; ++k) {
          EXPECT_GE(box.lo[k], parent.lo[k]);
          EXPECT_LE(box.hi[k], parent.hi[k]);
        }
        if (count > 0)
          check_leaf(box, ref, count);
        else
          walk(ref, box);
      }
    }
  };
  const Box everything{{-INFINITY, -INFINITY, -INFINITY}, {INFINITY, INFINITY, INFINITY}};
  walk(0, everything);
  for (int s : node_seen) EXPECT_EQ(s, 1);
  for (int s : tri_seen) EXPECT_EQ(s, 1);
  EXPECT_LE(required_stack_size(bvh_),
            static_cast<unsigned>(cl_->features().value(device::Feature::STACK_SIZE)));
}

INSTANTIATE_TEST_SUITE_P(Widths, AccelTest, ::testing::Values(2u, 4u),
                         [](const auto& info) { return "Bvh" + std::to_string(info.param); });

// The BVH4 traversal against the BVH2 one on the same scene and rays: the
// same triangle at the same distance (both run the same triangle test, so
// the distance is bit-identical), and the same any-hit answers.
TEST(AccelWidths, Bvh4AgreesWithBvh2) {
  auto ctx = device::Context::create("");
  ASSERT_TRUE(ctx.is_ok()) << ctx.status().to_string();
  SceneBuilder b;
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(-15, 15), a(0, 6.28);
  for (int i = 0; i < 250; ++i) {
    Mat4 xf = translate(u(rng), u(rng), u(rng));
    const double c = std::cos(a(rng)), s = std::sin(a(rng));
    xf.at(0, 0) = c;
    xf.at(0, 1) = -s;
    xf.at(1, 0) = s;
    xf.at(1, 1) = c;
    add_grid(b, 4, 3.0f, xf);
  }
  auto soup = build_triangle_soup(b.s);
  ASSERT_TRUE(soup.is_ok());
  auto bvh2 = build_bvh(soup.value(), BvhBuildOptions{.width = 2});
  ASSERT_TRUE(bvh2.is_ok());
  auto cl2 = ClTracer::create(*ctx.value(), bvh2.value());
  ASSERT_TRUE(cl2.is_ok());
  // Embree's 4-wide build and the collapsed binary tree.
  for (bool collapse : {false, true}) {
    SCOPED_TRACE(collapse ? "collapsed BVH2" : "Embree 4-wide build");
    auto bvh4 = build_bvh(soup.value(), BvhBuildOptions{.width = 4, .collapse = collapse});
    ASSERT_TRUE(bvh4.is_ok());
    EXPECT_LT(bvh4->stats.nodes, bvh2->stats.nodes);
    EXPECT_LE(bvh4->stats.max_depth, bvh2->stats.max_depth);
    if (collapse) EXPECT_EQ(bvh4->stats.leaves, bvh2->stats.leaves);  // the same leaves
    auto cl4 = ClTracer::create(*ctx.value(), bvh4.value());
    ASSERT_TRUE(cl4.is_ok());
    for (RayKind kind : {RayKind::kRandom, RayKind::kIncoherent, RayKind::kShadow}) {
      const auto rays = make_rays(soup.value(), kind, 20000, 5);
      auto h2 = cl2.value()->closest(rays);
      auto h4 = cl4.value()->closest(rays);
      auto o2 = cl2.value()->any(rays);
      auto o4 = cl4.value()->any(rays);
      ASSERT_TRUE(h2.is_ok() && h4.is_ok() && o2.is_ok() && o4.is_ok());
      size_t disagree = 0, hits = 0;
      for (size_t i = 0; i < rays.size(); ++i) {
        const auto& x = h2.value()[i];
        const auto& y = h4.value()[i];
        hits += x.prim >= 0;
        // Only an exact tie (coincident or edge-sharing triangles) may
        // differ in the triangle, never in the distance.
        disagree += x.prim != y.prim;
        EXPECT_EQ(x.t, y.t) << ray_kind_name(kind) << " ray " << i;
        EXPECT_EQ(o2.value()[i], o4.value()[i]) << ray_kind_name(kind) << " ray " << i;
      }
      EXPECT_LE(disagree, rays.size() / 2000) << ray_kind_name(kind);
      EXPECT_GT(hits, rays.size() / 20) << ray_kind_name(kind);
    }
  }
}

TEST(AccelWidths, PreferredWidthFollowsDeviceAndEnvironment) {
  device::DeviceInfo cpu, gpu;
  gpu.is_gpu = true;
  unsetenv("LUXEL_BVH_WIDTH");
  EXPECT_EQ(preferred_bvh_width(cpu), 4u);
  EXPECT_EQ(preferred_bvh_width(gpu), 2u);
  setenv("LUXEL_BVH_WIDTH", "2", 1);
  EXPECT_EQ(preferred_bvh_width(cpu), 2u);
  setenv("LUXEL_BVH_WIDTH", "4", 1);
  EXPECT_EQ(preferred_bvh_width(gpu), 4u);
  unsetenv("LUXEL_BVH_WIDTH");
  SceneBuilder b;
  auto soup = build_triangle_soup(b.s);
  ASSERT_TRUE(soup.is_ok());
  EXPECT_FALSE(build_bvh(soup.value(), BvhBuildOptions{.width = 3}).is_ok());
}

}  // namespace
}  // namespace luxel::accel
