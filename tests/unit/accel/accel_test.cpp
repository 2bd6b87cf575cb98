// BVH build, OpenCL traversal and the Embree tracer on hand-made scenes with
// known answers (no file import involved).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "accel/bvh_builder.h"
#include "accel/cl_tracer.h"
#include "accel/embree_intersector.h"
#include "accel/embree_tracer.h"
#include "accel/ray_gen.h"
#include "accel/triangle_soup.h"
#include "device/context.h"
#include "shared/ray_offset.h"

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

class AccelTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    auto ctx = device::Context::create("");
    ASSERT_TRUE(ctx.is_ok()) << ctx.status().to_string();
    ctx_ = std::move(ctx.value()).release();
  }
  static void TearDownTestSuite() { delete ctx_; }

  // Builds soup, BVH and both tracers for the scene.
  void build(const scene::Scene& s, BvhBuildOptions opt = {}) {
    auto soup = build_triangle_soup(s);
    ASSERT_TRUE(soup.is_ok()) << soup.status().to_string();
    soup_ = std::move(soup.value());
    auto bvh = build_bvh(soup_, opt);
    ASSERT_TRUE(bvh.is_ok()) << bvh.status().to_string();
    bvh_ = std::move(bvh.value());
    auto cl = ClTracer::create(*ctx_, bvh_);
    ASSERT_TRUE(cl.is_ok()) << cl.status().to_string();
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

  static device::Context* ctx_;
  TriangleSoup soup_;
  DeviceBvh bvh_;
  std::unique_ptr<ClTracer> cl_;
  std::unique_ptr<EmbreeTracer> embree_;
};
device::Context* AccelTest::ctx_ = nullptr;

TEST_F(AccelTest, SingleTriangleDistanceAndBarycentrics) {
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

TEST_F(AccelTest, EmptySceneMissesEverything) {
  SceneBuilder b;
  build(b.s);
  const auto rays = make_rays(soup_, RayKind::kRandom, 1000, 3);
  for (const auto& h : cl_closest(rays)) EXPECT_EQ(h.prim, -1);
  auto any = cl_->any(rays);
  ASSERT_TRUE(any.is_ok());
  for (int o : any.value()) EXPECT_EQ(o, 0);
}

TEST_F(AccelTest, ClosestOfOverlappingLayersAndOriginalIds) {
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

TEST_F(AccelTest, WatertightAtSharedEdgesAndVertices) {
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

TEST_F(AccelTest, OffsetRaysDoNotSelfIntersectAtLargeCoordinates) {
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

TEST_F(AccelTest, AlphaMaskCutsOutAndMatchesEmbree) {
  // A quad whose texture is transparent on the left half (u < 0.5).
  SceneBuilder b;
  scene::Texture tex;
  tex.width = 4;
  tex.height = 1;
  tex.rgba = {1, 1, 1, 0, 1, 1, 1, 0.2f, 1, 1, 1, 1, 1, 1, 1, 0.9f};
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
  ASSERT_TRUE(cl_->features().has("ALPHA_MASK"));
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

TEST_F(AccelTest, OpaqueScenesCompileWithoutAlphaCode) {
  SceneBuilder b;
  add_grid(b, 2, 1.0f);
  build(b.s);
  EXPECT_FALSE(cl_->features().has("ALPHA_MASK"));
  EXPECT_TRUE(bvh_.uvs.empty());
}

TEST_F(AccelTest, RandomRaysAgreeWithEmbreeOnAClutteredScene) {
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
  EXPECT_GT(bvh_.stats.max_depth, 8u);
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
TEST_F(AccelTest, IndexedQueriesAgreeAcrossBackends) {
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

TEST_F(AccelTest, BvhStatsAreConsistent) {
  SceneBuilder b;
  add_grid(b, 20, 10.0f);
  build(b.s, BvhBuildOptions{.max_leaf_size = 4});
  EXPECT_EQ(bvh_.stats.triangles, 800u);
  EXPECT_EQ(bvh_.triangles.size(), 800u);
  // A binary tree: leaves = inner nodes + 1 (no absent children here).
  EXPECT_EQ(bvh_.stats.leaves, bvh_.stats.nodes + 1);
  EXPECT_GT(bvh_.stats.sah_cost, 0.0);
  // Every soup triangle appears exactly once in leaf order.
  std::vector<int> seen(800, 0);
  for (const auto& t : bvh_.triangles) seen[static_cast<size_t>(cl::as_int(t.v0.w))]++;
  for (int s : seen) EXPECT_EQ(s, 1);
}

}  // namespace
}  // namespace luxel::accel
