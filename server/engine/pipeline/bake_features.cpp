#include "pipeline/bake_features.h"

namespace luxel::pipeline {
namespace {

// The lights whose unshadowed irradiance kernels/shading/analytic_light.h
// computes in closed form (lux_light_is_analytic, mirrored).
size_t analytic_light_count(const LightTable& table) {
  size_t n = 0;
  for (const cl::LuxLight& l : table.lights) {
    const int type = LUX_LIGHT_TYPE(l);
    if ((type == LUX_LIGHT_TYPE_TRIANGLE && !(LUX_LIGHT_FLAGS(l) & LUX_LIGHT_FLAG_TEXTURED)) ||
        type == LUX_LIGHT_TYPE_POINT || type == LUX_LIGHT_TYPE_SPOT ||
        (type == LUX_LIGHT_TYPE_DIRECTIONAL && !(LUX_LIGHT_ONE_MINUS_COS(l) > 0.0f)))
      ++n;
  }
  return n;
}

}  // namespace

device::FeatureSet derive_bake_features(const BakeSettings& settings, const LightTable& lights,
                                        const SceneData& data, const EncodingPlan& plan) {
  device::FeatureSet f;
  add_light_features(lights, &f);
  if (!lights.lights.empty()) f.set("NEE");
  if (data.uses_textures) f.set("TEXTURES");
  if (data.uses_emissive_texture && lights.has_emissive) f.set("EMISSIVE_TEXTURE");
  if (data.needs_specular) f.set("SPECULAR");
  if (data.uses_normal_map) f.set("NORMAL_MAP");
  if (data.uses_texcoord1 &&
      (f.has("TEXTURES") || f.has("EMISSIVE_TEXTURE") || f.has("NORMAL_MAP")))
    f.set("TEXCOORD1");
  if (settings.sort_directions) f.set("SORT_DIRECTIONS");
  if (settings.compaction) f.set("COMPACTION");
  if (settings.adaptive) f.set("ADAPTIVE");
  if (settings.filter == Filter::kGaussian) f.set("FILTER_GAUSSIAN");
  if (settings.random_sequence) f.set("SEQUENCE_RANDOM");
  if (!plan.empty()) f.set("BASIS");
  // Analytic direct light: irradiance lightmaps only (directional encodings
  // keep plain NEE), and only when some light has a closed form, so other
  // scenes compile nothing new. Every path loops over the light table once
  // (kernels/bake/raygen.h), hence the cap on the table's size.
  if (settings.direct == DirectLight::kAnalytic && plan.empty() &&
      lights.lights.size() <= kMaxAnalyticLightTable && analytic_light_count(lights) > 0)
    f.set("DIRECT_ANALYTIC");
  return f;
}

}  // namespace luxel::pipeline
