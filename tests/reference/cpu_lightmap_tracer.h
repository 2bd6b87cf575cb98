// An independent CPU reference for lightmap bakes: a small, plain path
// tracer (Embree for rays, std::thread over texels) that estimates the same
// quantity as the engine (pipeline::bake) so the two can be compared
// statistically (tests/integration/reference_agreement_test.cpp).
//
// The quantity, per texel (thesis §3.4):
//   value = mean over the texel's valid Hammersley sample positions (each
//           with equal probability; atlas/sample_info.h) of the irradiance
//           E(x) = integral over the hemisphere of L_in(x, w) cos(n_s, w) dw
//   at the position's surface point x, with respect to the interpolated,
//   normalised shading normal n_s; directions below the geometric surface
//   contribute 0. Units are radiometric, glTF values used 1:1.
// Light transport, with B = max_bounces indirect bounces after the texel
// point: emission is collected at hit vertices 1..B+1, scattering happens at
// vertices 1..B (surfaces hit from behind shaded like the front): Lambert
// (f = base_color / pi) in scenes of rough dielectrics only, otherwise the
// glTF BRDF with multiple-scattering compensation (reference_bsdf.h).
// Emission = emissive_factor * emissive_strength, from the front face only
// unless the material is double sided (the winding's, the clockwise one
// under a mirroring instance: glTF 2.0 §3.7.4).
//
// Estimator: next-event estimation only (thesis §6.1). At every vertex
// k = 0..B one point is sampled uniformly by area on the emitters and its
// unoccluded contribution added; emission that an extension ray happens to
// hit is never added (it is the light the previous vertex's NEE accounts
// for). Extension rays at vertex 0 and at Lambertian vertices are
// cosine-sampled about the shading normal; at glTF-BRDF vertices they are
// drawn from GgxBrdf::sample (a cosine / GGX mixture) and weighted by
// f cos / pdf. No Russian roulette, no MIS, no clamping: every sample is
// an independent, unbiased estimate, so the per-texel sample variance is a
// valid error estimate. Each texel has its own PCG32 stream (seeded by the
// bake seed and the texel), so results do not depend on threading.
#pragma once

#include <cstdint>
#include <vector>

#include "atlas/atlas.h"
#include "common/status.h"
#include "reference/reference_bsdf.h"
#include "scene/scene.h"

namespace luxel::reference {

struct ReferenceSettings {
  uint32_t samples_per_texel = 1024;  // every covered texel gets exactly this many
  int max_bounces = 3;                // indirect bounces after the texel point
  uint64_t seed = 1;
  unsigned threads = 2;
  // The BRDF of glTF-BRDF scenes. Anything but kGltf is a deliberate error,
  // for tests that show the agreement check detects it.
  BrdfModel brdf = BrdfModel::kGltf;
};

// Channels of ReferenceLightmap::mean / variance.
enum Channel : int { kRed = 0, kGreen = 1, kBlue = 2, kLuminance = 3, kChannels = 4 };

struct ReferenceLightmap {
  int width = 0, height = 0;
  // Per texel: valid sample positions / 64 (the engine's alpha); 0 = uncovered.
  std::vector<float> coverage;
  std::vector<uint32_t> samples;  // per texel
  // Per texel and channel (index texel * kChannels + channel): the mean of
  // the texel's samples and the unbiased variance of ONE sample (divisor
  // n - 1). Luminance is Rec. 709 of each sample, kept separately because
  // its variance is not a sum of the colour channels' variances.
  std::vector<double> mean;
  std::vector<double> variance;
  uint64_t paths = 0;
  double seconds = 0;

  double mean_of(size_t texel, int channel) const { return mean[texel * kChannels + channel]; }
  // Standard error of the texel's mean: sqrt(variance / samples).
  double std_error(size_t texel, int channel) const;
};

// Bakes every covered texel of `atlas` (built by atlas::build_atlas for
// `scene`). INVALID_ARGUMENT for settings out of range and for scenes with
// what the reference does not model (reference_scene.h).
Result<ReferenceLightmap> bake_reference(const scene::Scene& scene, const atlas::Atlas& atlas,
                                         const ReferenceSettings& settings);

}  // namespace luxel::reference
