// Sample-info buffer (thesis §4.2) and its decode (§4.3), checked against an
// independent brute-force point-in-triangle test on scenes built in code.
#include "kernels/shared/sample_info.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <random>

#include "atlas_test_util.h"

namespace luxel::atlas::testing {
namespace {

AtlasSettings at_resolution(int side) {
  AtlasSettings s;
  s.resolution = side;
  return s;
}

uint64_t valid_mask(const SampleInfo& info, uint32_t texel) {
  const uint32_t o = info.offsets[texel];
  return info.words[o] | uint64_t{info.words[o + 1]} << 32;
}

// Invariants every sample-info buffer must satisfy.
void expect_consistent(const SampleInfo& info) {
  uint64_t valid = 0, records = 0;
  uint32_t previous = 0;
  for (size_t k = 0; k < info.covered_texels.size(); ++k) {
    const uint32_t texel = info.covered_texels[k];
    if (k > 0) EXPECT_GT(texel, previous);
    previous = texel;
    const uint64_t mask = valid_mask(info, texel);
    EXPECT_NE(mask, 0u);
    valid += static_cast<uint64_t>(std::popcount(mask));
    records += record_count(info, k);
    uint64_t uni = 0;
    const uint32_t o = info.offsets[texel];
    for (size_t r = 0; r < record_count(info, k); ++r) {
      const uint32_t* rec = &info.words[o + 2 + 4 * r];
      uni |= rec[0] | uint64_t{rec[1]} << 32;
    }
    EXPECT_EQ(uni, mask);
  }
  size_t with_offset = 0;
  for (uint32_t o : info.offsets) with_offset += o != LUX_NO_SAMPLES;
  EXPECT_EQ(with_offset, info.covered_texels.size());
  EXPECT_EQ(valid, info.valid_samples);
  EXPECT_EQ(records, info.records);
}

TEST(Hammersley, StratifiedAndExact) {
  std::vector<int> columns(64, 0), rows(64, 0);
  for (uint32_t i = 0; i < 64; ++i) {
    const cl::float2 p = cl::lux_hammersley64(i);
    EXPECT_EQ(p.x, static_cast<float>(i) / 64.0f);
    uint32_t reversed = 0;
    for (int bit = 0; bit < 6; ++bit) reversed |= ((i >> bit) & 1u) << (5 - bit);
    EXPECT_EQ(p.y, static_cast<float>(reversed) / 64.0f);
    ++columns[static_cast<size_t>(p.x * 64)];
    ++rows[static_cast<size_t>(p.y * 64)];
  }
  for (int c : columns) EXPECT_EQ(c, 1);
  for (int r : rows) EXPECT_EQ(r, 1);
}

TEST(NthSetBit, MatchesALinearScan) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20000; ++trial) {
    uint32_t word = rng();
    if (trial % 3 == 1) word &= rng();  // sparser words
    if (trial % 3 == 2) word |= rng();  // denser words
    uint32_t n = 0;
    for (uint32_t bit = 0; bit < 32; ++bit)
      if (word >> bit & 1u) EXPECT_EQ(cl::lux_nth_set_bit(word, n++), bit) << word;
  }
}

TEST(SampleInfo, FullQuadCoversEveryTexel) {
  SceneBuilder b;
  b.instance(add_quad(b, 0, 0, 1, 1));
  const int side = 16;
  const Atlas atlas = expect_atlas(b.scene, at_resolution(side));
  const SampleInfo info = expect_sample_info(b.scene, atlas);
  expect_consistent(info);
  ASSERT_EQ(info.covered_texels.size(), static_cast<size_t>(side * side));
  EXPECT_EQ(info.valid_samples, uint64_t{64} * side * side);
  EXPECT_EQ(info.zero_uv_area_triangles, 0u);
  for (size_t k = 0; k < info.covered_texels.size(); ++k) {
    const uint32_t texel = info.covered_texels[k];
    EXPECT_EQ(valid_mask(info, texel), ~uint64_t{0});
    const size_t n = record_count(info, k);
    // The diagonal (0,0)-(1,1) only crosses the texels (k, k).
    EXPECT_EQ(n, texel % side == texel / side ? 2u : 1u) << texel;
  }
  // On the diagonal, both triangles claim the Hammersley points with x == y.
  int on_diagonal = 0;
  for (uint32_t i = 0; i < 64; ++i) on_diagonal += hammersley_x(i) == hammersley_y(i);
  EXPECT_EQ(info.contested_samples, static_cast<uint64_t>(on_diagonal * side));
  EXPECT_EQ(info.bytes(), (info.offsets.size() + info.words.size()) * 4);
}

// A convex polygon split into a fan around an inner point: every sample
// position strictly inside the polygon must be covered, also on the shared
// edges. Vertices are random, some snapped to the 1/64 grid so edges run
// exactly through sample positions.
TEST(SampleInfo, SharedEdgesLeaveNoGaps) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> jitter(-0.02f, 0.02f);
  for (int trial = 0; trial < 24; ++trial) {
    const int n = 3 + trial % 9;
    const float cx = 0.5f + jitter(rng), cy = 0.5f + jitter(rng);
    std::vector<Vec2> uv = {{cx, cy}};
    for (int k = 0; k < n; ++k) {
      const double angle =
          2 * M_PI * (k + 0.3 * std::uniform_real_distribution<double>(0, 1)(rng)) / n;
      float u = static_cast<float>(0.5 + 0.45 * std::cos(angle)),
            v = static_cast<float>(0.5 + 0.45 * std::sin(angle));
      if (trial % 2) {  // snap to sample positions of a 32^2 atlas
        u = std::round(u * 2048) / 2048;
        v = std::round(v * 2048) / 2048;
      }
      uv.push_back({u, v});
    }
    std::vector<uint32_t> idx;
    for (uint32_t k = 0; k < static_cast<uint32_t>(n); ++k)
      idx.insert(idx.end(), {0, 1 + k, 1 + (k + 1) % n});
    SceneBuilder b;
    b.instance(b.add_mesh(uv, idx));
    const Atlas atlas = expect_atlas(b.scene, at_resolution(32));
    const SampleInfo info = expect_sample_info(b.scene, atlas);
    expect_consistent(info);
    // Strictly inside the polygon: at least 1e-7 texel inside every outer
    // edge (v_k, v_k+1). Points near the inner, shared edges and the centre
    // are exactly the ones a non-watertight rasteriser would drop.
    const auto tris = world_triangles(b.scene, atlas);
    auto inside_polygon = [&](double px, double py) {
      for (const auto& t : tris) {
        const TexelTriangle& f = t.texel;
        const double area2 =
            (f.x[1] - f.x[0]) * (f.y[2] - f.y[0]) - (f.y[1] - f.y[0]) * (f.x[2] - f.x[0]);
        const double ex = f.x[2] - f.x[1], ey = f.y[2] - f.y[1];
        const double side = (ex * (py - f.y[1]) - ey * (px - f.x[1])) / std::hypot(ex, ey);
        if ((area2 >= 0 ? side : -side) <= 1e-7) return false;
      }
      return true;
    };
    int inside_points = 0;
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 32; ++x)
        for (uint32_t i = 0; i < 64; ++i) {
          if (!inside_polygon(x + hammersley_x(i), y + hammersley_y(i))) continue;
          ++inside_points;
          const uint32_t texel = static_cast<uint32_t>(y * 32 + x);
          const bool covered =
              info.offsets[texel] != LUX_NO_SAMPLES && (valid_mask(info, texel) >> i & 1u);
          EXPECT_TRUE(covered) << "trial " << trial << " texel " << x << "," << y << " sample "
                               << i;
        }
    EXPECT_GT(inside_points, 0);
  }
}

TEST(SampleInfo, TinyTriangleInsideOneTexel) {
  SceneBuilder b;
  const float s = 1.0f / 16;
  b.instance(b.add_mesh({{5.1f * s, 7.2f * s}, {5.6f * s, 7.3f * s}, {5.3f * s, 7.8f * s}},
                        {0, 1, 2}, {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}));
  const Atlas atlas = expect_atlas(b.scene, at_resolution(16));
  const SampleInfo info = expect_sample_info(b.scene, atlas);
  expect_consistent(info);
  ASSERT_EQ(info.covered_texels.size(), 1u);
  EXPECT_EQ(info.covered_texels[0], 7u * 16 + 5);
  EXPECT_EQ(info.records, 1u);
  const TexelTriangle t = texel_triangle(b.scene, atlas, 0, 0);
  uint64_t expected = 0;
  for (uint32_t i = 0; i < 64; ++i)
    if (inside_margin(t, 5 + hammersley_x(i), 7 + hammersley_y(i)) >= 0)
      expected |= uint64_t{1} << i;
  EXPECT_NE(expected, 0u);
  EXPECT_EQ(valid_mask(info, info.covered_texels[0]), expected);
}

TEST(SampleInfo, ZeroUvAreaTrianglesAreSkippedAndCounted) {
  SceneBuilder b;
  // Two good triangles and one whose UVs are collinear, instanced twice.
  const int mesh =
      b.add_mesh({{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0.5f, 0.5f}}, {0, 1, 2, 0, 2, 3, 0, 4, 2},
                 {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5f, 0.5f, 1}});
  b.instance(mesh);
  b.instance(mesh, scale_translate(1, 1, 1, 3));
  const Atlas atlas = expect_atlas(b.scene, at_resolution(64));
  const SampleInfo info = expect_sample_info(b.scene, atlas);
  EXPECT_EQ(info.zero_uv_area_triangles, 2u);
  // No record refers to the collinear triangle (index 2 of either instance).
  for (size_t k = 0; k < info.covered_texels.size(); ++k)
    for (size_t r = 0; r < record_count(info, k); ++r)
      EXPECT_NE(info.words[info.offsets[info.covered_texels[k]] + 2 + 4 * r + 3], 2u);
}

// Random overlapping triangles (some smaller than a texel, some slivers) in
// two meshes; every sample position is checked against brute force.
SceneBuilder random_triangles(uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0, 1);
  SceneBuilder b;
  for (int m = 0; m < 2; ++m) {
    std::vector<Vec2> uv;
    std::vector<uint32_t> idx;
    for (int t = 0; t < 25; ++t) {
      const float size = t % 5 == 0 ? 0.01f : t % 5 == 1 ? 0.3f : 0.1f;
      const float cx = 0.5f * m + 0.05f + 0.4f * unit(rng), cy = 0.05f + 0.9f * unit(rng);
      for (int k = 0; k < 3; ++k) {
        idx.push_back(static_cast<uint32_t>(uv.size()));
        float u = cx + size * (unit(rng) - 0.5f), v = cy + size * (unit(rng) - 0.5f);
        if (t % 7 == 3 && k == 2) {  // sliver: third vertex near the first edge's midpoint
          u = 0.5f * (uv[uv.size() - 2].x + uv[uv.size() - 1].x) + 1e-4f;
          v = 0.5f * (uv[uv.size() - 2].y + uv[uv.size() - 1].y);
        }
        uv.push_back({std::clamp(u, 0.5f * m, 0.5f * m + 0.5f), std::clamp(v, 0.0f, 1.0f)});
      }
    }
    b.instance(b.add_mesh(uv, idx));
  }
  return b;
}

TEST(SampleInfo, DecodeMatchesBruteForce) {
  for (uint32_t seed : {1u, 2u, 3u}) {
    const SceneBuilder b = random_triangles(seed);
    const int side = 48;
    const Atlas atlas = expect_atlas(b.scene, at_resolution(side));
    ASSERT_EQ(atlas.mode, AtlasMode::kShared);
    const SampleInfo info = expect_sample_info(b.scene, atlas);
    expect_consistent(info);
    const auto tris = world_triangles(b.scene, atlas);
    size_t checked = 0;
    for (uint32_t texel = 0; texel < static_cast<uint32_t>(side * side); ++texel) {
      const bool covered = info.offsets[texel] != LUX_NO_SAMPLES;
      const uint64_t mask = covered ? valid_mask(info, texel) : 0;
      for (uint32_t i = 0; i < 64; ++i) {
        const double px = texel % side + hammersley_x(i), py = texel / side + hammersley_y(i);
        int first_strict = -1, first_loose = -1;
        for (size_t j = 0; j < tris.size(); ++j) {
          const double m = inside_margin(tris[j].texel, px, py);
          if (m > 1e-9 && first_strict < 0) first_strict = static_cast<int>(j);
          if (m > -1e-9 && first_loose < 0) first_loose = static_cast<int>(j);
        }
        const bool valid = mask >> i & 1u;
        if (first_strict >= 0) EXPECT_TRUE(valid) << "texel " << texel << " sample " << i;
        if (first_loose < 0) EXPECT_FALSE(valid) << "texel " << texel << " sample " << i;
        if (!valid) continue;
        const auto rank = static_cast<uint32_t>(std::popcount(mask & ((uint64_t{1} << i) - 1)));
        const SamplePoint p = sample_point(info, texel, rank);
        EXPECT_EQ(p.hammersley_index, i);
        EXPECT_EQ(p.x, px);
        EXPECT_EQ(p.y, py);
        size_t j = 0;
        while (j < tris.size() &&
               !(tris[j].instance == p.instance && tris[j].triangle == p.triangle))
          ++j;
        ASSERT_LT(j, tris.size());
        EXPECT_GT(inside_margin(tris[j].texel, px, py), -1e-9);
        if (first_strict >= 0)
          EXPECT_LE(j, static_cast<size_t>(first_strict)) << "not the first record";
        ++checked;
      }
    }
    EXPECT_EQ(checked, info.valid_samples);
  }
}

TEST(SampleInfo, BarycentricsReconstructTheSamplePoint) {
  const SceneBuilder b = random_triangles(5);
  const Atlas atlas = expect_atlas(b.scene, at_resolution(64));
  const SampleInfo info = expect_sample_info(b.scene, atlas);
  double worst_float = 0;
  for (uint32_t texel : info.covered_texels) {
    const uint32_t count = cl::lux_sample_info_count(info.words.data(), info.offsets[texel]);
    for (uint32_t rank = 0; rank < count; ++rank) {
      const SamplePoint p = sample_point(info, texel, rank);
      const TexelTriangle t = texel_triangle(b.scene, atlas, p.instance, p.triangle);
      const Vec3 w = atlas_barycentrics(t, p.x, p.y);
      EXPECT_NEAR(w.x + w.y + w.z, 1.0, 1e-6);
      EXPECT_TRUE(w.x >= 0 && w.y >= 0 && w.z >= 0);
      const double x = w.x * t.x[0] + w.y * t.x[1] + w.z * t.x[2];
      const double y = w.x * t.y[0] + w.y * t.y[1] + w.z * t.y[2];
      EXPECT_NEAR(x, p.x, 1e-4);
      EXPECT_NEAR(y, p.y, 1e-4);
      // The float device helper (run on the host) agrees with the double one.
      const auto& mesh = b.scene.meshes[static_cast<size_t>(b.scene.instances[p.instance].mesh)];
      cl::float2 uv[3];
      for (int k = 0; k < 3; ++k) {
        const Vec2 a = atlas.to_atlas(
            p.instance, mesh.uv1[mesh.indices[p.triangle * 3 + static_cast<uint32_t>(k)]]);
        uv[k] = {a.x, a.y};
      }
      float f[3];
      cl::lux_texel_barycentrics(uv[0], uv[1], uv[2], 64.0f, 64.0f, texel % 64, texel / 64,
                                 cl::lux_hammersley64(p.hammersley_index), &f[0], &f[1], &f[2]);
      EXPECT_NEAR(f[0] + f[1] + f[2], 1.0f, 1e-6f);
      const double d =
          std::max({std::fabs(f[0] - w.x), std::fabs(f[1] - w.y), std::fabs(f[2] - w.z)});
      worst_float = std::max(worst_float, d);
    }
  }
  EXPECT_LT(worst_float, 1e-3);
  std::printf("float vs double barycentrics: worst weight difference %.3g\n", worst_float);
}

TEST(SampleInfo, Deterministic) {
  const SceneBuilder b = random_triangles(9);
  const Atlas atlas = expect_atlas(b.scene, at_resolution(40));
  const SampleInfo first = expect_sample_info(b.scene, atlas);
  const SampleInfo second = expect_sample_info(b.scene, atlas);
  EXPECT_EQ(first.offsets, second.offsets);
  EXPECT_EQ(first.words, second.words);
  EXPECT_GT(first.contested_samples, 0u);  // the random triangles overlap
}

TEST(SampleInfo, RejectsAnAtlasOfAnotherScene) {
  const SceneBuilder b = random_triangles(1);
  Atlas atlas = expect_atlas(b.scene, at_resolution(16));
  atlas.placements.pop_back();
  auto info = build_sample_info(b.scene, atlas);
  ASSERT_FALSE(info.is_ok());
  EXPECT_EQ(info.status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace luxel::atlas::testing
