// Chart packing into one lightmap atlas with bit images (thesis Ch. 4.1,
// §4.1.1-4.1.3): every shape is rasterised into a conservative texel mask,
// the mask is dilated by the padding, and shapes are placed largest first at
// the first position (row by row, then column) where the dilated mask misses
// every texel already covered, tested 64 texels at a time.
//
// The packer only places; it never scales. Shapes arrive in texel units (the
// caller has multiplied chart UVs by texels per unit) and leave with a
// rotation and an offset:
//
//   atlas_texel(p) = rotate(p, rotation) + offset
//   rotate(p, 0) = ( x,  y)    rotate(p, 1) = (-y,  x)
//   rotate(p, 2) = (-x, -y)    rotate(p, 3) = ( y, -x)
//
// in the atlas's texel coordinates (texel (i, j) is the square
// [i, i+1] x [j, j+1]; divide by width/height for UVs in [0, 1]). Rotation 1
// turns +x into +y: counter-clockwise with y up, clockwise as an image with
// row 0 at the top. The offset is computed in double; the caller should apply
// it in double before rounding to float.
//
// Conservative mask: texel (i, j) belongs to a shape when one of its closed
// triangles touches the closed square [i - e, i+1 + e] x [j - e, j+1 + e],
// e = kMaskSlopTexels: a texel touched only along an edge or at a corner
// counts, which covers every Hammersley sample position the bake can assign
// to the shape (atlas/texel_raster.h: inclusive edges) plus float rounding of
// the final UVs. Each placed shape sits at an integer texel plus a fraction
// that centres it in its mask, so its mask spans floor(extent + 2e) + 1 texels
// on each axis (a shape exactly 4 texels wide covers 5, one 3.5 wide covers 4).
//
// Guarantees: the placed masks of two shapes are at least `padding_texels`
// empty texels apart (Chebyshev: the mask of one dilated by padding never
// meets the mask of another), every mask lies at least `padding_texels` from
// the atlas border, a shape with allow_rotation = false keeps rotation 0, and
// the output is a deterministic function of the input.
#pragma once

#include <vector>

#include "common/cancel.h"
#include "common/math.h"
#include "common/status.h"

namespace luxel::uv {

// How far beyond a texel's square a triangle may pass and still count as
// touching it (texel units).
constexpr double kMaskSlopTexels = 1e-4;

struct PackShape {
  std::vector<Vec2> corners;   // 3 per triangle, texel units, any origin
  bool allow_rotation = true;  // charts may turn by quarter turns; instance layouts may not
};

struct PackOptions {
  // Empty texels kept between the masks of two shapes and between a mask and
  // the atlas border. >= 0.
  int padding_texels = 2;
  // Fixed atlas size in texels (both > 0), or both 0: the smallest square
  // whose side is a multiple of 4 that holds every shape, found by starting at
  // sqrt(footprint / 0.88) + padding (footprint: see pack_shapes) and growing
  // by 2.5 % until the shapes fit.
  int width = 0, height = 0;
  // Largest side the automatic size may reach (and a fixed size may have).
  int max_resolution = 8192;
  // Polled before each size tried: a request ends the packing with
  // cancelled_error (common/cancel.h).
  CancelToken cancel;
};

struct ShapePlacement {
  int rotation = 0;             // quarter turns, 0..3 (see rotate() above)
  double offset[2] = {0, 0};    // texels, added after rotation
  int mask_origin[2] = {0, 0};  // texel of the mask's first row and column
  int mask_size[2] = {0, 0};    // mask width and height in texels (after rotation)
};

struct PackResult {
  int width = 0, height = 0;               // atlas size in texels
  std::vector<ShapePlacement> placements;  // in input order
  long long covered_texels = 0;            // sum of the shapes' mask texel counts
  long long footprint_texels = 0;          // sum of the masks dilated by padding towards +x, +y
  double efficiency = 0;                   // covered_texels / (width * height)
  int attempts = 0;                        // atlas sizes tried (1 for a fixed size)
};

// Places `shapes` in one atlas. Shapes go in order of size bucket (mask
// perimeter, 4 buckets per octave), then mask area, then input order. Each
// of a shape's (up to 4 distinct) turns is placed at its first free position
// in row-major order, searched from where the previous shape went when both
// share a bucket and from the top otherwise (thesis §4.1, steps 4-6); the
// turn whose padded mask ends highest wins, then the leftmost, then the
// lower rotation.
//
// Errors: INVALID_ARGUMENT for a shape without triangles or whose corner
// count is not a multiple of 3, a non-finite corner, negative padding, a
// size with one side 0 or beyond max_resolution, max_resolution < 1.
// RESOURCE_EXHAUSTED when the shapes do not fit the fixed size, or when the
// automatic size would exceed max_resolution (the message names both).
//
// The footprint used for the first automatic size is the sum over shapes of
// the mask dilated by `padding` towards +x and +y only: shapes `padding`
// apart have disjoint such footprints, so no side below
// sqrt(footprint) + padding can hold them.
Result<PackResult> pack_shapes(const std::vector<PackShape>& shapes, const PackOptions& options);

}  // namespace luxel::uv
