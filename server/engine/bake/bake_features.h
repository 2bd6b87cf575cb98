// What one bake compiles in: the FeatureSet derived from the scene's lights
// and materials, the settings' switches and the requested encodings. It
// becomes the -D options of kernels/bake.cl (its module comment lists them),
// decides which buffers are uploaded and which stages run, and is reported
// with the bake. The one place where a feature is derived.
#pragma once

#include "bake/encodings.h"
#include "bake/scene_data.h"
#include "device/feature_set.h"
#include "settings/bake_settings.h"
#include "shading/light_table.h"

namespace luxel::pipeline {

// Analytic direct light (DIRECT_ANALYTIC) loops over the whole light table
// for every path; past this many lights the bake keeps plain NEE.
inline constexpr size_t kMaxAnalyticLightTable = 4096;
// direct = auto takes the analytic form only for tables up to this size (a
// few punctual lights beside the sky and sun): the per-path loop stays short.
inline constexpr size_t kMaxAutoAnalyticLightTable = 64;

device::FeatureSet derive_bake_features(const BakeSettings& settings, const LightTable& lights,
                                        const SceneData& data, const EncodingPlan& plan);

}  // namespace luxel::pipeline
