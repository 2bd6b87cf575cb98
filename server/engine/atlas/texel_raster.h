// Rasterising lightmap-UV triangles onto the 64 sample positions of each
// texel (thesis §4.2: "precompute the triangle and instance indices for each
// of those sample positions").
//
// Positions are in texel units (atlas UV x atlas size, row 0 at the top); a
// sample position is texel (x, y) + lux_hammersley64(i), exact in double.
// Edges are inclusive and evaluated watertight: each edge function is
// computed from the edge's endpoints in a canonical order (lexicographically
// smaller first) and negated for the triangle that sees the edge reversed, so
// the two triangles of a shared edge get exactly opposite values and every
// position on or near the edge is inside at least one of them.
#pragma once

#include <cstdint>

#include "atlas/atlas.h"
#include "scene/scene.h"

namespace luxel::atlas {

struct TexelTriangle {
  double x[3] = {0, 0, 0}, y[3] = {0, 0, 0};
};

// Texel-space vertices of triangle `triangle` of instance `instance`: the
// float atlas UVs (Atlas::to_atlas, what the device is given) times the atlas
// size, in double. Indices must be valid.
TexelTriangle texel_triangle(const scene::Scene& scene, const Atlas& atlas, uint32_t instance,
                             uint32_t triangle);

// Texel-space x, y of Hammersley point i (0..63) within its texel.
double hammersley_x(uint32_t i);
double hammersley_y(uint32_t i);

class TriangleCoverage {
 public:
  explicit TriangleCoverage(const TexelTriangle& triangle);

  // Zero area (see is_zero_area): covers nothing, counted by the caller.
  bool zero_area() const { return zero_area_; }

  // Rows [begin, end) the triangle touches, clamped to [0, height).
  void rows(int height, int* begin, int* end) const;
  // Columns [begin, end) of row y the triangle touches (its intersection with
  // the strip y <= Y <= y + 1, widened by 1e-6 texel), clamped to [0, width).
  void row_span(int y, int width, int* begin, int* end) const;
  // Bit i set when sample position i of texel (x, y) is inside the triangle.
  uint64_t texel_mask(int x, int y) const;

 private:
  struct Edge {
    double ax, ay, dx, dy;  // canonical start point and direction
    double sign;            // +-1: orientation of the triangle x canonical order
    double eval(double px, double py) const { return sign * (dx * (py - ay) - dy * (px - ax)); }
  };
  TexelTriangle t_;
  Edge edges_[3];
  bool zero_area_ = false;
};

}  // namespace luxel::atlas
