// Lightmap UV seams: surface edges that appear at two different places in
// the atlas. Two triangles of one mesh share a world-space edge (the same two
// vertex positions), but their lightmap UVs put that edge in two charts (or
// two parts of one chart). An engine's bilinear fetch on either side then
// reads different texels, and unless those agree the surface shows a line
// along the edge (output/seam_stitch.h makes them agree).
//
// Edges are matched within one mesh by their endpoints' object-space
// positions, quantised to 2^-20 of the mesh's largest extent (split vertices
// carry bit-identical or nearly identical copies of one position). An edge
// is a seam when exactly two triangles share it, their shading normals agree
// at both endpoints (within about 2.6 degrees: at a hard edge the lighting is
// discontinuous by nature, so it is counted, not stitched) and its two
// lightmap images differ by more than 1e-3 texel at either endpoint; an edge
// shared by three or more triangles (non-manifold) is skipped and counted. Every instance of
// a mesh gets its own copies of the mesh's seams, placed by the atlas.
#pragma once

#include <cstddef>
#include <vector>

#include "atlas/atlas.h"
#include "common/math.h"
#include "scene/scene.h"

namespace luxel::atlas {

// One seam edge on one lightmap page, in page-local texel units (texel
// (x, y) covers [x, x+1) x [y, y+1), atlas.h). a0 and b0 are the two images
// of the same surface vertex, a1 and b1 those of the edge's other vertex, so
// a0 + t (a1 - a0) and b0 + t (b1 - b0) image the same surface point.
struct SeamEdge {
  uint32_t instance = 0;
  int page = 0;
  Vec2 a0, a1, b0, b1;
  // Width in texels of the narrower of the two charts the seam joins (the
  // shorter side of each chart's bounding box in the atlas): the stitcher
  // leaves seams of charts too narrow to hold a bilinear footprint alone.
  float chart_texels = 0;
};

struct SeamSet {
  std::vector<SeamEdge> edges;
  size_t cross_page = 0;    // seams whose two sides lie on different pages: skipped
  size_t non_manifold = 0;  // edges of more than two triangles (per instance): skipped
  size_t hard_edges = 0;    // shared edges whose normals differ (per instance): not seams
  size_t degenerate = 0;    // seams with a zero-length side in the atlas: skipped
};

// Seams of every instance of `scene` laid out by `atlas` (the scene the bake
// reads, with its lightmap UVs in uv1). Deterministic: edges are listed by
// instance, then by quantised position.
SeamSet find_seams(const scene::Scene& scene, const Atlas& atlas);

}  // namespace luxel::atlas
