// The light table a bake uploads for next-event estimation (thesis §6.1):
// every light as a cl::LuxLight, an alias table selecting by power (§6.3.2), the map
// from world triangles to emissive lights, and the sky with its importance-
// sampling distribution. Device side: kernels/shading/lights.h; layout and
// units: kernels/shared/light.h.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "accel/triangle_soup.h"
#include "common/math.h"
#include "common/status.h"
#include "device/feature_set.h"
#include "kernels/shared/light.h"
#include "scene/scene.h"
#include "shading/light_settings.h"

namespace luxel::pipeline {

struct LightTable {
  // Order: scene punctual lights (scene order), the settings sun, emissive
  // triangles (TriangleSoup order), the sky last. Lights with zero power are
  // left out (counted in dropped_zero_power).
  std::vector<cl::LuxLight> lights;
  // One alias entry per light (shading/cdf.h): light i is
  // chosen with probability select[i].pmf, proportional to its power. Empty
  // when there are no lights.
  std::vector<cl::LuxAliasEntry> select;
  // Per world triangle (TriangleSoup order): its light index, or -1.
  std::vector<int32_t> triangle_light;

  cl::LuxSky sky{};               // kind NONE unless a sky with power > 0
  std::vector<float> sky_texels;  // width * height * 3 (rgb radiance), image sky only
  // Two-level importance sampling (shading/sky_distribution.h;
  // layout in kernels/shared/light.h): blocks per cell of receiver normals,
  // texels per block.
  std::vector<float> sky_block_cdfs;
  std::vector<float> sky_texel_cdfs;

  // Which light types are present (after dropping): decide the FeatureSet,
  // so kernels carry no code for absent types (see add_light_features).
  bool has_point = false, has_spot = false, has_directional = false, has_emissive = false;
  bool has_sky = false, sky_is_image = false;

  // Sum of selection powers (W, luminance-weighted; directional lights and
  // the sky over the scene's bounding disc).
  double total_power = 0;
  size_t dropped_zero_power = 0;

  size_t bytes() const;
};

// Builds the table. Power used for selection:
//   point        4 pi I                  spot     2 pi (1 - cos((inner + outer) / 2)) I
//   directional  E pi r^2                sky      pi L_mean pi r^2
//   triangle     pi A L (x2 if double-sided, x the emissive texture's mean luminance)
// with luminances of the rgb values and r the radius of scene_bounds'
// bounding sphere (1 if the bounds are empty). Errors (INVALID_ARGUMENT) name
// the light, material, setting or file: negative or non-finite intensities,
// colours, spot angles, sun direction; an unreadable, negative or non-finite
// sky image.
Result<LightTable> build_light_table(const scene::Scene& scene, const accel::TriangleSoup& soup,
                                     const LightSettings& settings, const Bounds3& scene_bounds);

// Sets LIGHT_POINT, LIGHT_SPOT, LIGHT_DIRECTIONAL, LIGHT_EMISSIVE and SKY or
// SKY_IMAGE for the light types the table holds (none for absent types).
void add_light_features(const LightTable& table, device::FeatureSet* features);

}  // namespace luxel::pipeline
