#include "pipeline/bake_features.h"

namespace luxel::pipeline {

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
  return f;
}

}  // namespace luxel::pipeline
