// Per-texel guides of the lightmap denoiser (denoise.h): where each covered
// texel lies on the surface, which way it faces, and which chart it belongs
// to. Built on the host from the atlas and the sample-info buffer (thesis
// §4.2), in the layout kernels/shared/denoise.h documents.
#pragma once

#include <cstdint>
#include <vector>

#include "atlas/atlas.h"
#include "atlas/sample_info.h"
#include "kernels/shared/compat.h"
#include "scene/scene.h"

namespace luxel::pipeline {

struct DenoiseGuides {
  int width = 0, height = 0;
  // xyz: world position, the mean over those of up to kGuideSamples of the
  // texel's valid sample positions that lie on the texel's chart; w: world
  // length of one texel side there (sqrt of world area per texel area of
  // their triangles); w = 0: texel not covered.
  std::vector<cl::float4> position;
  std::vector<cl::float4> normal;  // xyz: unit mean shading normal; w unused
  // Chart id: the chart most of those samples lie on (a texel on a chart
  // border also covers its neighbour's triangles). A chart is a set of triangles of one instance
  // connected through shared lightmap-UV vertices (equal TEXCOORD_1 values), numbered over all
  // instances, so instances never share ids.
  std::vector<uint32_t> chart;
};

inline constexpr uint32_t kGuideSamples = 8;

// `scene` must be the one `atlas` and `info` were built from.
DenoiseGuides build_denoise_guides(const scene::Scene& scene, const atlas::Atlas& atlas,
                                   const atlas::SampleInfo& info);

// Chart of every triangle of `mesh` (0 .. count-1), connected through equal
// TEXCOORD_1 values at their vertices; returns the count.
uint32_t label_uv_charts(const scene::Mesh& mesh, std::vector<uint32_t>& chart_of_triangle);

}  // namespace luxel::pipeline
