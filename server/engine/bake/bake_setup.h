// Everything a bake derives from its scene and settings before the first
// path: the atlas and its sample-info buffer (§4.2), the triangle soup, BVH
// and tracer, the light table, the device surface records, the encoding
// plan, the compiled features, the kernel constants and the batch size.
#pragma once

#include <memory>

#include "accel/bvh_builder.h"
#include "accel/intersector.h"
#include "accel/triangle_soup.h"
#include "atlas/atlas.h"
#include "atlas/sample_info.h"
#include "bake/encodings.h"
#include "bake/scene_data.h"
#include "common/cancel.h"
#include "device/context.h"
#include "device/feature_set.h"
#include "kernels/shared/bake.h"
#include "scene/scene.h"
#include "settings/bake_settings.h"
#include "shading/light_table.h"

namespace luxel::pipeline {

struct BakeSetup {
  atlas::Atlas atlas;
  atlas::SampleInfo info;
  accel::TriangleSoup soup;
  std::unique_ptr<accel::DeviceBvh> bvh;       // kept: the Embree backend reads it in place
  std::unique_ptr<accel::Intersector> tracer;  // the ray queries (settings.intersector)
  LightTable lights;
  SceneData data;
  EncodingPlan plan;
  device::FeatureSet features;  // bake.cl's (the tracer's are its own)
  cl::LuxBakeParams params{};   // per-bake constants; paths/first_path set per iteration
  size_t capacity = 0;          // path slots per iteration
  // Iterations start small and grow (BakePolicy::next_batch): the radiance
  // cache with an automatic batch learns between iterations.
  bool grow_batches = false;
  // Probe domain (bake_probe_domain in bake.h): one float4 per probe, the
  // position and the visibility cap in w; the atlas is then probes x 1
  // "texels" and the sample info a stand-in. Empty for lightmaps.
  std::vector<cl::float4> probes;
};

// The probe domain a bake traces instead of the lightmap's texels.
struct ProbeDomain {
  std::vector<Vec3> positions;
  std::vector<float> max_distance;  // per probe: the visibility cap (a miss counts as it)
};

// Slot ids share a word with the 3-bit octant tag of direction sorting (§5.4).
inline constexpr uint32_t kSlotMask = 0x1FFFFFFFu;  // LUX_SLOT_MASK in kernels/bake/path.h
inline constexpr int kTagShift = 29;

// `atlas` is the scene's lightmap layout (lightmap_layout.h).
// INVALID_ARGUMENT when no texel of the lightmap holds a sample;
// RESOURCE_EXHAUSTED past 2^29 covered texels; errors of the BVH, light
// table, encodings and tracer as they come.
// probes: a probe domain instead of the atlas's texels (then `atlas` is
// ignored); its settings.encodings must be SH in the world frame.
// The sample info of a laid-out atlas (atlas::build_sample_info), refused
// when no texel is covered or too many are for 32-bit path keys: the first
// step of prepare_bake, also run at submit on small layouts
// (job::check_bake_job).
Result<atlas::SampleInfo> covered_sample_info(const scene::Scene& scene, const atlas::Atlas& atlas,
                                              CancelToken cancel = {});

// cancel: polled between the steps and by the BVH build; a request ends
// the setup with cancelled_error (common/cancel.h).
Result<BakeSetup> prepare_bake(const scene::Scene& scene, atlas::Atlas atlas,
                               const BakeSettings& settings, device::Context& ctx,
                               const ProbeDomain* probes = nullptr, CancelToken cancel = {});

}  // namespace luxel::pipeline
