// The per-texel sample-info buffer (thesis §4.2) and its host decode.
//
// Every texel has 64 fixed sample positions (the 64-point Hammersley set,
// lux_hammersley64). For each texel the buffer stores which positions lie on
// geometry and, per instance-triangle pair, which of them it covers; ray
// generation picks a valid position at random and decodes the instance and
// triangle under it (§4.3, Listing 4.2, lux_sample_info_lookup). The word
// layout is documented in kernels/shared/sample_info.h.
//
// Build: every world triangle is rasterised in texel units (texel_raster.h)
// band by band (a few rows at a time, so memory stays at the output size plus
// one band's worth of coverage tuples); within a band the tuples are bucketed
// by texel with a counting sort that keeps them in (instance, triangle)
// order. Zero-UV-area triangles are skipped and counted.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "atlas/atlas.h"
#include "atlas/texel_raster.h"
#include "common/cancel.h"
#include "common/math.h"
#include "common/status.h"
#include "scene/scene.h"

namespace luxel::atlas {

struct SampleInfo {
  int width = 0, height = 0;
  // width * height; first word of each texel in `words`, or LUX_NO_SAMPLES
  // (0xFFFFFFFF) for a texel without valid samples.
  std::vector<uint32_t> offsets;
  // Per covered texel: valid mask lo, hi, then records {coverage lo,
  // coverage hi, instance, mesh triangle} (4 words each).
  std::vector<uint32_t> words;
  // Ascending texel indices y * width + x with at least one valid sample.
  std::vector<uint32_t> covered_texels;
  uint64_t valid_samples = 0;         // set bits over all valid masks
  uint64_t records = 0;               // instance-triangle records over all texels
  uint64_t contested_samples = 0;     // valid samples covered by more than one record
  size_t zero_uv_area_triangles = 0;  // world triangles skipped (counted per instance)

  // Bytes of the two device buffers (offsets + words).
  size_t bytes() const { return (offsets.size() + words.size()) * sizeof(uint32_t); }
};

// cancel: polled per band of rows; a request ends it with cancelled_error.
Result<SampleInfo> build_sample_info(const scene::Scene& scene, const Atlas& atlas,
                                     CancelToken cancel = {});

// The sum of the coverage (the share of a texel's 64 sample positions on
// geometry, the weight of kernels/bake/stats.h and adaptive.h) of covered
// slots [begin, end). A sum of multiples of 1/64: exact.
double coverage_sum(const SampleInfo& info, size_t begin, size_t end);

// One decoded sample position (host twin of lux_sample_info_lookup).
struct SamplePoint {
  uint32_t instance = 0, triangle = 0;
  uint32_t hammersley_index = 0;
  double x = 0, y = 0;  // texel-space position: texel + lux_hammersley64(index)
};

// The rank-th valid sample of `texel` (rank < number of valid samples; the
// texel must be covered).
SamplePoint sample_point(const SampleInfo& info, uint32_t texel, uint32_t rank);

// Barycentric weights (of vertices 0, 1, 2) of texel-space point (x, y) in
// the triangle, computed in double (§3.4) and clamped to the triangle (no
// negative weight, sum 1), so a sample on an edge yields a point on the
// triangle. A zero-area triangle yields its centroid.
Vec3 atlas_barycentrics(const TexelTriangle& triangle, double x, double y);

}  // namespace luxel::atlas
