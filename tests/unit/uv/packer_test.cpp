// The BitImage chart packer (uv/bitimage_packer.h), checked by an overlap
// checker of its own: placed triangles are sampled at 16 x 16 points per
// texel, each shape's sampled texels are dilated by the padding, and no
// dilated texel may belong to another shape, nor any sampled texel to the
// border. The checker shares no code with the packer.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "uv/bitimage_packer.h"

namespace luxel::uv {
namespace {

// --- Shapes -----------------------------------------------------------------

void add_triangle(PackShape* s, double ax, double ay, double bx, double by, double cx, double cy) {
  s->corners.push_back({static_cast<float>(ax), static_cast<float>(ay)});
  s->corners.push_back({static_cast<float>(bx), static_cast<float>(by)});
  s->corners.push_back({static_cast<float>(cx), static_cast<float>(cy)});
}

void add_rect(PackShape* s, double x, double y, double w, double h) {
  add_triangle(s, x, y, x + w, y, x + w, y + h);
  add_triangle(s, x, y, x + w, y + h, x, y + h);
}

PackShape rect_shape(double x, double y, double w, double h) {
  PackShape s;
  add_rect(&s, x, y, w, h);
  return s;
}

// Rectangles, L shapes and triangles with log-uniform sizes in
// [1, max_size] texels, turned by arbitrary angles, at arbitrary origins.
std::vector<PackShape> random_shapes(uint32_t seed, int count, double max_size) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<PackShape> shapes;
  for (int i = 0; i < count; ++i) {
    const double a = std::exp(u(rng) * std::log(max_size));
    const double b = a * (0.3 + 0.7 * u(rng));
    PackShape s;
    const int kind = static_cast<int>(u(rng) * 3);
    if (kind == 0) {
      add_rect(&s, 0, 0, a, b);
    } else if (kind == 1) {
      add_rect(&s, 0, 0, a, b * 0.4);
      add_rect(&s, 0, b * 0.4, a * 0.4, b * 0.6);
    } else {
      add_triangle(&s, 0, 0, a, 0, a * u(rng), b);
    }
    const double angle = u(rng) < 0.5 ? 0 : u(rng) * 6.283185307179586;
    const double c = std::cos(angle), sn = std::sin(angle);
    const double ox = (u(rng) - 0.5) * 1000, oy = (u(rng) - 0.5) * 1000;
    for (Vec2& p : s.corners) {
      const double x = p.x, y = p.y;
      p = {static_cast<float>(c * x - sn * y + ox), static_cast<float>(sn * x + c * y + oy)};
    }
    s.allow_rotation = u(rng) < 0.8;
    shapes.push_back(std::move(s));
  }
  return shapes;
}

// --- The independent checker ---------------------------------------------

struct P2 {
  double x, y;
};

P2 place(const Vec2& v, const ShapePlacement& pl) {
  const double x = v.x, y = v.y;
  double rx = x, ry = y;
  if (pl.rotation == 1) rx = -y, ry = x;
  if (pl.rotation == 2) rx = -x, ry = -y;
  if (pl.rotation == 3) rx = y, ry = -x;
  return {rx + pl.offset[0], ry + pl.offset[1]};
}

double edge(P2 a, P2 b, P2 p) {
  return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
}

// Empty string when the placement is valid, else what is wrong.
std::string check_packing(const std::vector<PackShape>& shapes, const PackResult& r, int padding) {
  constexpr int kSub = 16;
  const int w = r.width, h = r.height;
  if (r.placements.size() != shapes.size()) return "placement count";
  std::vector<int> owner(static_cast<size_t>(w) * h, -1);
  std::vector<std::vector<int>> texels(shapes.size());  // per shape: y * w + x
  for (size_t s = 0; s < shapes.size(); ++s) {
    const ShapePlacement& pl = r.placements[s];
    if (pl.rotation < 0 || pl.rotation > 3) return "rotation out of range";
    for (size_t t = 0; t < shapes[s].corners.size(); t += 3) {
      P2 q[3];
      for (int c = 0; c < 3; ++c) q[c] = place(shapes[s].corners[t + c], pl);
      for (int c = 0; c < 3; ++c) {
        if (q[c].x < padding || q[c].y < padding || q[c].x > w - padding || q[c].y > h - padding)
          return "shape " + std::to_string(s) + ": a corner is in the border";
      }
      const double area = edge(q[0], q[1], q[2]);
      if (area == 0) continue;
      const double sign = area > 0 ? 1 : -1;
      const int x0 = static_cast<int>(std::floor(std::min({q[0].x, q[1].x, q[2].x})));
      const int x1 = static_cast<int>(std::floor(std::max({q[0].x, q[1].x, q[2].x})));
      const int y0 = static_cast<int>(std::floor(std::min({q[0].y, q[1].y, q[2].y})));
      const int y1 = static_cast<int>(std::floor(std::max({q[0].y, q[1].y, q[2].y})));
      for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) {
          bool hit = false;
          for (int k = 0; k < kSub * kSub && !hit; ++k) {
            const P2 p{x + (k % kSub + 0.5) / kSub, y + (k / kSub + 0.5) / kSub};
            hit = sign * edge(q[0], q[1], p) >= 0 && sign * edge(q[1], q[2], p) >= 0 &&
                  sign * edge(q[2], q[0], p) >= 0;
          }
          if (!hit) continue;
          if (x < padding || y < padding || x >= w - padding || y >= h - padding)
            return "shape " + std::to_string(s) + " covers a border texel";
          if (x < pl.mask_origin[0] || y < pl.mask_origin[1] ||
              x >= pl.mask_origin[0] + pl.mask_size[0] || y >= pl.mask_origin[1] + pl.mask_size[1])
            return "shape " + std::to_string(s) + " covers a texel outside its reported mask";
          int& o = owner[static_cast<size_t>(y) * w + x];
          if (o >= 0 && o != static_cast<int>(s))
            return "shapes " + std::to_string(o) + " and " + std::to_string(s) + " share a texel";
          if (o < 0) texels[s].push_back(y * w + x);
          o = static_cast<int>(s);
        }
      }
    }
  }
  for (size_t s = 0; s < shapes.size(); ++s) {
    for (const int t : texels[s]) {
      const int x = t % w, y = t / w;
      for (int dy = -padding; dy <= padding; ++dy) {
        for (int dx = -padding; dx <= padding; ++dx) {
          const int o = owner[static_cast<size_t>(y + dy) * w + (x + dx)];
          if (o >= 0 && o != static_cast<int>(s))
            return "shapes " + std::to_string(s) + " and " + std::to_string(o) +
                   " are closer than the padding";
        }
      }
    }
  }
  return "";
}

// --- Tests ------------------------------------------------------------------

TEST(BitImagePacker, RandomShapesKeepPaddingAndBorder) {
  for (const uint32_t seed : {1u, 2u, 3u, 4u, 5u}) {
    for (const int padding : {0, 1, 2, 3}) {
      const auto shapes = random_shapes(seed, 300, 24);
      PackOptions o;
      o.padding_texels = padding;
      const auto r = pack_shapes(shapes, o);
      ASSERT_TRUE(r) << r.status().to_string();
      EXPECT_EQ(r->width, r->height);
      EXPECT_EQ(r->width % 4, 0);
      EXPECT_EQ(check_packing(shapes, r.value(), padding), "")
          << "seed " << seed << " padding " << padding;
      for (size_t i = 0; i < shapes.size(); ++i) {
        if (!shapes[i].allow_rotation) EXPECT_EQ(r->placements[i].rotation, 0) << i;
      }
      EXPECT_DOUBLE_EQ(r->efficiency,
                       static_cast<double>(r->covered_texels) / (r->width * r->height));
    }
  }
}

TEST(BitImagePacker, CheckerCatchesAnOverlap) {
  const auto shapes = random_shapes(7, 200, 16);
  const auto r = pack_shapes(shapes, {});
  ASSERT_TRUE(r) << r.status().to_string();
  ASSERT_EQ(check_packing(shapes, r.value(), 2), "");
  PackResult bad = r.value();
  // Shape 1 moved onto shape 0's place (same rotation, same offset).
  bad.placements[1] = bad.placements[0];
  bad.placements[1].offset[0] += 0.25;
  EXPECT_NE(check_packing(shapes, bad, 2), "");
}

// A k x k grid of equal squares each covering m x m texels, padding p apart
// and from the border, fills a square of side k * (m + p) + p exactly.
struct Grid {
  std::vector<PackShape> shapes;
  int side;
};

Grid square_grid(int k, double square, int mask_texels, int padding) {
  Grid g;
  for (int i = 0; i < k * k; ++i) g.shapes.push_back(rect_shape(3.3 * i, -7.1 * i, square, square));
  g.side = k * (mask_texels + padding) + padding;
  return g;
}

TEST(BitImagePacker, EqualSquaresFillTheExactSize) {
  // Side 0.99 covers one texel; side 1 (and 3) touches one more texel along
  // its far edges, conservatively: 2 (and 4).
  const struct {
    double square;
    int mask;
  } cases[] = {{0.99, 1}, {1.0, 2}, {3.0, 4}, {2.5, 3}};
  for (const auto& c : cases) {
    for (const int padding : {0, 1, 2, 3}) {
      const Grid g = square_grid(6, c.square, c.mask, padding);
      PackOptions o;
      o.padding_texels = padding;
      o.width = o.height = g.side;
      const auto r = pack_shapes(g.shapes, o);
      ASSERT_TRUE(r) << c.square << " " << padding << ": " << r.status().to_string();
      EXPECT_EQ(check_packing(g.shapes, r.value(), padding), "");
      EXPECT_EQ(r->covered_texels, 36LL * c.mask * c.mask);
      // One texel less on either side leaves room for 5 rows or columns only.
      o.width = g.side - 1;
      const auto narrow = pack_shapes(g.shapes, o);
      ASSERT_FALSE(narrow);
      EXPECT_EQ(narrow.status().code(), StatusCode::kResourceExhausted);
      o.width = g.side;
      o.height = g.side - 1;
      EXPECT_EQ(pack_shapes(g.shapes, o).status().code(), StatusCode::kResourceExhausted);
    }
  }
}

TEST(BitImagePacker, CheckerCatchesAOneTexelShift) {
  // In the exact grid every neighbour sits at the padding, so moving any
  // square by one texel towards a neighbour (or the border) is an error.
  const int padding = 2;
  const Grid g = square_grid(4, 3.0, 4, padding);
  PackOptions o;
  o.padding_texels = padding;
  o.width = o.height = g.side;
  const auto r = pack_shapes(g.shapes, o);
  ASSERT_TRUE(r) << r.status().to_string();
  ASSERT_EQ(check_packing(g.shapes, r.value(), padding), "");
  for (size_t s = 0; s < g.shapes.size(); ++s) {
    for (const int axis : {0, 1}) {
      for (const double d : {-1.0, 1.0}) {
        PackResult bad = r.value();
        bad.placements[s].offset[axis] += d;
        EXPECT_NE(check_packing(g.shapes, bad, padding), "") << s << " " << axis << " " << d;
      }
    }
  }
}

TEST(BitImagePacker, CoveredTexelsOfRectanglesFollowTheClosedForm) {
  // A rectangle of extent e covers floor(e + 2 * 1e-4) + 1 texels per axis.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.2, 20);
  std::vector<PackShape> shapes;
  long long expected = 0;
  for (int i = 0; i < 200; ++i) {
    const double w = i % 5 == 0 ? std::floor(u(rng)) + 1 : u(rng);
    const double h = i % 7 == 0 ? std::floor(u(rng)) + 1 : u(rng);
    shapes.push_back(rect_shape(0.125 * i, 0.5 * i, w, h));
    // The extents the packer sees: of the float corners, in double.
    const double fw =
        static_cast<double>(static_cast<float>(0.125 * i + w)) - static_cast<float>(0.125 * i);
    const double fh =
        static_cast<double>(static_cast<float>(0.5 * i + h)) - static_cast<float>(0.5 * i);
    expected += static_cast<long long>(std::floor(fw + 2e-4) + 1) *
                static_cast<long long>(std::floor(fh + 2e-4) + 1);
  }
  const auto r = pack_shapes(shapes, {});
  ASSERT_TRUE(r) << r.status().to_string();
  EXPECT_EQ(r->covered_texels, expected);
  EXPECT_EQ(check_packing(shapes, r.value(), 2), "");
}

TEST(BitImagePacker, RotationOnlyWhenAllowed) {
  // Upright 3 x 30 bars fit a 128 x 16 atlas only lying down.
  std::vector<PackShape> bars(4, rect_shape(5, 5, 3, 30));
  PackOptions o;
  o.padding_texels = 1;
  o.width = 128;
  o.height = 16;
  const auto turned = pack_shapes(bars, o);
  ASSERT_TRUE(turned) << turned.status().to_string();
  EXPECT_EQ(check_packing(bars, turned.value(), 1), "");
  for (const ShapePlacement& p : turned->placements) EXPECT_EQ(p.rotation % 2, 1);
  for (PackShape& b : bars) b.allow_rotation = false;
  const auto upright = pack_shapes(bars, o);
  ASSERT_FALSE(upright);
  EXPECT_EQ(upright.status().code(), StatusCode::kResourceExhausted);
}

TEST(BitImagePacker, Deterministic) {
  const auto shapes = random_shapes(21, 500, 32);
  const auto a = pack_shapes(shapes, {});
  const auto b = pack_shapes(shapes, {});
  ASSERT_TRUE(a && b);
  ASSERT_EQ(a->width, b->width);
  for (size_t i = 0; i < shapes.size(); ++i) {
    EXPECT_EQ(a->placements[i].rotation, b->placements[i].rotation);
    EXPECT_EQ(a->placements[i].offset[0], b->placements[i].offset[0]);
    EXPECT_EQ(a->placements[i].offset[1], b->placements[i].offset[1]);
  }
}

TEST(BitImagePacker, AutomaticSizeIsBoundedByMaxResolution) {
  // The exact grid needs its side: nothing below it can hold the squares'
  // disjoint footprints, so an automatic size limited below it must fail.
  const int padding = 2;
  const Grid g = square_grid(6, 3.0, 4, padding);
  PackOptions o;
  o.padding_texels = padding;
  const auto r = pack_shapes(g.shapes, o);
  ASSERT_TRUE(r) << r.status().to_string();
  EXPECT_GE(r->width, g.side);
  EXPECT_EQ(check_packing(g.shapes, r.value(), padding), "");
  o.max_resolution = g.side - 1;
  const auto small = pack_shapes(g.shapes, o);
  ASSERT_FALSE(small);
  EXPECT_EQ(small.status().code(), StatusCode::kResourceExhausted);
  EXPECT_NE(small.status().message().find("max_resolution " + std::to_string(o.max_resolution)),
            std::string::npos)
      << small.status().message();
  // A limit at the size found changes nothing.
  const auto shapes = random_shapes(3, 400, 24);
  const auto free = pack_shapes(shapes, {});
  ASSERT_TRUE(free);
  o = {};
  o.max_resolution = free->width;
  const auto same = pack_shapes(shapes, o);
  ASSERT_TRUE(same) << same.status().to_string();
  EXPECT_EQ(same->width, free->width);
}

TEST(BitImagePacker, RejectsBadInput) {
  PackOptions o;
  std::vector<PackShape> shapes{rect_shape(0, 0, 4, 4)};
  ASSERT_TRUE(pack_shapes(shapes, o));
  o.padding_texels = -1;
  EXPECT_EQ(pack_shapes(shapes, o).status().code(), StatusCode::kInvalidArgument);
  o = {};
  o.width = 64;  // height 0
  EXPECT_EQ(pack_shapes(shapes, o).status().code(), StatusCode::kInvalidArgument);
  o = {};
  shapes.push_back({});
  EXPECT_EQ(pack_shapes(shapes, o).status().code(), StatusCode::kInvalidArgument);
  shapes.back() = rect_shape(0, 0, 1, 1);
  shapes.back().corners.pop_back();
  EXPECT_EQ(pack_shapes(shapes, o).status().code(), StatusCode::kInvalidArgument);
  shapes.back() = rect_shape(0, 0, 1, 1);
  shapes.back().corners[2].y = std::nanf("");
  const auto nan = pack_shapes(shapes, o);
  EXPECT_EQ(nan.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(nan.status().message().find("shape 1 corner 2"), std::string::npos);
  shapes.back() = rect_shape(0, 0, 1e7, 1);
  EXPECT_EQ(pack_shapes(shapes, o).status().code(), StatusCode::kResourceExhausted);
}

TEST(BitImagePacker, EmptyInputGivesASmallAtlas) {
  const auto r = pack_shapes({}, {});
  ASSERT_TRUE(r);
  EXPECT_TRUE(r->placements.empty());
  EXPECT_EQ(r->covered_texels, 0);
}

}  // namespace
}  // namespace luxel::uv
