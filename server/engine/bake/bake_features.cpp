#include "bake/bake_features.h"

namespace luxel::pipeline {
namespace {

// The lights whose unshadowed irradiance kernels/shading/analytic_light.h
// computes in closed form (lux_light_is_analytic, mirrored), split into
// emissive triangles (Lambert's polygon formula) and punctual lights.
struct AnalyticLights {
  size_t triangles = 0, punctual = 0;
};

AnalyticLights analytic_lights(const LightTable& table) {
  AnalyticLights n;
  for (const cl::LuxLight& l : table.lights) {
    const int type = LUX_LIGHT_TYPE(l);
    if (type == LUX_LIGHT_TYPE_TRIANGLE && !(LUX_LIGHT_FLAGS(l) & LUX_LIGHT_FLAG_TEXTURED))
      ++n.triangles;
    else if (type == LUX_LIGHT_TYPE_POINT || type == LUX_LIGHT_TYPE_SPOT ||
             (type == LUX_LIGHT_TYPE_DIRECTIONAL && !(LUX_LIGHT_ONE_MINUS_COS(l) > 0.0f)))
      ++n.punctual;
  }
  return n;
}

// Whether `direct` means the analytic form for this light table.
// kAuto: where the equal-time measurements of docs/accuracy.md ("Time to
// equal error") show it winning or even. With punctual lights (exact
// unshadowed irradiance, sampled in proportion to it) the foliage scene
// reaches equal error 5x sooner and the lights courtyard as soon; with
// emissive triangles the loop over the table in raygen costs more than the
// exact polygon irradiance saves (Cornell boxes: 0.87-0.93x), so a scene
// with any analytic triangle keeps plain NEE, as does a long table.
bool wants_analytic(DirectLight direct, const LightTable& table) {
  const AnalyticLights n = analytic_lights(table);
  if (n.triangles + n.punctual == 0 || table.lights.size() > kMaxAnalyticLightTable) return false;
  switch (direct) {
    case DirectLight::kAnalytic:
      return true;
    case DirectLight::kSampled:
      return false;
    case DirectLight::kAuto:
      break;
  }
  return n.triangles == 0 && table.lights.size() <= kMaxAutoAnalyticLightTable;
}

}  // namespace

device::FeatureSet derive_bake_features(const BakeSettings& settings, const LightTable& lights,
                                        const SceneData& data, const EncodingPlan& plan) {
  using device::Feature;
  device::FeatureSet f;
  add_light_features(lights, &f);
  if (!lights.lights.empty()) f.set(Feature::NEE);
  if (data.uses_textures) f.set(Feature::TEXTURES);
  if (data.uses_emissive_texture && lights.has_emissive) f.set(Feature::EMISSIVE_TEXTURE);
  if (data.needs_specular) f.set(Feature::SPECULAR);
  if (data.uses_normal_map) f.set(Feature::NORMAL_MAP);
  if (data.uses_texcoord1 &&
      (f.has(Feature::TEXTURES) || f.has(Feature::EMISSIVE_TEXTURE) || f.has(Feature::NORMAL_MAP)))
    f.set(Feature::TEXCOORD1);
  if (settings.sort_directions) f.set(Feature::SORT_DIRECTIONS);
  if (settings.compaction) f.set(Feature::COMPACTION);
  if (settings.adaptive) f.set(Feature::ADAPTIVE);
  // The cache gathers at the first hit and holds max_bounces - 1 bounces:
  // nothing to gather without a bounce, and shards must merge exactly.
  if (settings.radiance_cache && settings.max_bounces >= 1 && !settings.sharded())
    f.set(Feature::RADIANCE_CACHE);
  // Guiding reweights the first direction, which directional encodings
  // assume uniform: irradiance lightmaps only.
  if (settings.guiding && plan.empty()) f.set(Feature::GUIDING);
  if (settings.filter == Filter::kGaussian) f.set(Feature::FILTER_GAUSSIAN);
  if (settings.random_sequence) f.set(Feature::SEQUENCE_RANDOM);
  if (!plan.empty()) f.set(Feature::BASIS);
  // Analytic direct light: irradiance lightmaps only (directional encodings
  // keep plain NEE), and only when some light has a closed form, so other
  // scenes compile nothing new. Every path loops over the light table once
  // (kernels/bake/raygen.h), hence the cap on the table's size.
  if (plan.empty() && wants_analytic(settings.direct, lights)) f.set(Feature::DIRECT_ANALYTIC);
  return f;
}

}  // namespace luxel::pipeline
