#include "bake/bake_setup.h"

#include <algorithm>

#include "accel/bvh_builder.h"
#include "bake/bake_features.h"
#include "bake/bake_policy.h"
#include "bake/iteration_stops.h"
#include "bake/resource_estimate.h"
#include "kernels/shared/probe.h"

namespace luxel::pipeline {

Result<atlas::SampleInfo> covered_sample_info(const scene::Scene& scene, const atlas::Atlas& atlas,
                                              CancelToken cancel) {
  auto info = atlas::build_sample_info(scene, atlas, cancel);
  if (!info) return info.status();
  if (info.value().covered_texels.empty())
    return invalid_argument(strprintf(
        "no texel of the %dx%d lightmap contains a sample of any triangle (lightmap UVs too "
        "small for this resolution?)",
        atlas.width, atlas.height));
  if (info.value().covered_texels.size() >= kSlotMask)
    return resource_exhausted("lightmap has too many covered texels for 32-bit path keys");
  return info;
}

Result<BakeSetup> prepare_bake(const scene::Scene& scene, atlas::Atlas atlas,
                               const BakeSettings& settings, device::Context& ctx,
                               const ProbeDomain* probes, CancelToken cancel) {
  BakeSetup s;
  if (probes) {
    // The probe domain: probe i is "texel" (i, 0) of a probes x 1 atlas,
    // every probe covered. The sample info is a stand-in (all 64 sample
    // positions valid, so the outputs' coverage is 1); the probe raygen
    // (kernels/bake/raygen.h) reads the probe buffer instead.
    const size_t n = probes->positions.size();
    if (n == 0) return invalid_argument("settings.probes: no probe to bake");
    if (n >= kSlotMask) return resource_exhausted("settings.probes: too many probes");
    s.atlas.width = static_cast<int>(n);
    s.atlas.height = 1;
    s.info.width = s.atlas.width;
    s.info.height = 1;
    s.info.offsets.resize(n);
    s.info.covered_texels.resize(n);
    s.info.words.reserve(n * 6);
    s.probes.resize(n);
    for (size_t i = 0; i < n; ++i) {
      s.info.offsets[i] = static_cast<uint32_t>(i * 6);
      s.info.covered_texels[i] = static_cast<uint32_t>(i);
      s.info.words.insert(s.info.words.end(),
                          {0xFFFFFFFFu, 0xFFFFFFFFu, 0xFFFFFFFFu, 0xFFFFFFFFu, 0u, 0u});
      const Vec3 p = probes->positions[i];
      s.probes[i] = {p.x, p.y, p.z, probes->max_distance[i]};
    }
    s.info.valid_samples = n * 64;
    s.info.records = n;
  } else {
    s.atlas = std::move(atlas);
    auto info = covered_sample_info(scene, s.atlas, cancel);
    if (!info) return info.status();
    s.info = std::move(info.value());
  }
  LUXEL_RETURN_IF_ERROR(check_cancel(cancel, "the sample info"));

  auto soup = accel::build_triangle_soup(scene);
  if (!soup) return soup.status();
  s.soup = std::move(soup.value());
  LUXEL_RETURN_IF_ERROR(check_cancel(cancel, "the triangle soup"));
  // The node width is the device's (BVH4 on CPUs, docs/performance.md).
  accel::BvhBuildOptions bvh_options;
  bvh_options.width = accel::preferred_bvh_width(ctx.info());
  bvh_options.cancel = cancel;
  auto bvh = accel::build_bvh(s.soup, bvh_options);
  if (!bvh) return bvh.status();
  s.bvh = std::make_unique<accel::DeviceBvh>(std::move(bvh.value()));
  auto tracer = accel::make_intersector(settings.intersector, ctx, *s.bvh);
  if (!tracer) return tracer.status();
  s.tracer = std::move(tracer.value());
  LUXEL_RETURN_IF_ERROR(check_cancel(cancel, "the intersector's setup"));

  auto lights = build_light_table(scene, s.soup, settings.lights, s.soup.bounds);
  if (!lights) return lights.status();
  s.lights = std::move(lights.value());
  auto data = prepare_scene_data(scene, s.soup, s.atlas, s.lights.triangle_light);
  if (!data) return data.status();
  s.data = std::move(data.value());
  LUXEL_RETURN_IF_ERROR(check_cancel(cancel, "the scene data"));
  auto plan = plan_encodings(settings.encodings);
  if (!plan) return plan.status();
  s.plan = std::move(plan.value());
  if (probes) {
    for (const Encoding& e : s.plan.encodings)
      if (e.tangent_frame || e.basis.describe().name.rfind("sh", 0) != 0)
        return invalid_argument(strprintf(
            "settings.encodings: probes take SH (sh1, sh2) only, not '%s'", e.name().c_str()));
    if (s.plan.empty()) return invalid_argument("settings.encodings: probes need sh1 or sh2");
    // The visibility bins follow the encodings in each probe's record.
    s.plan.stride += LUX_PROBE_VIS_BINS;
  }
  s.features = derive_bake_features(settings, s.lights, s.data, s.plan);
  if (probes) {
    s.features.set(device::Feature::PROBES);
    s.features.set(device::Feature::RADIANCE_CACHE, 0);  // probes have no texels to gather from
    s.features.set(device::Feature::GUIDING, 0);
  }

  // Batch size: the paths-per-iteration budget (the device's for auto,
  // resource_estimate.h), at most the device's iteration cap
  // (iteration_stops.h: stop requests wait for no more), never more than
  // the samples the whole bake needs, and at most 2^29 (slot ids share a
  // word with the octant tag).
  const uint64_t covered = s.info.covered_texels.size();
  const uint64_t requested =
      batch_paths_request(settings, DeviceLimits::of(ctx.info()), path_state_bytes(!s.plan.empty()),
                          memory_budget(settings, ctx.info().global_mem_bytes));
  uint64_t cap = std::min<uint64_t>(requested, iteration_path_cap(ctx.info().compute_units));
  if (settings.shard_samples() > 0)
    cap = std::min<uint64_t>(cap, uint64_t{settings.shard_samples()} * covered);
  // The radiance cache and the guide learn between iterations, so that a
  // small lightmap's first iteration must not take most of the bake before
  // either has learned anything. With an automatic batch:
  //  - the guide's iterations hold at most 16 samples per covered texel (at
  //    least 2^15 paths): a batch that straddles one of its epochs teaches
  //    nothing past the boundary (bake/guiding.h);
  //  - the cache's start at that size and then grow to the samples already
  //    traced (BakePolicy::next_batch): the cache then always holds at least
  //    half of a texel's samples, and later iterations run at the full
  //    batch. Iterations of 2^15 paths trace 8-13 % fewer paths per second
  //    than of 2^18 on the 64^2 peer scenes (docs/performance.md).
  if (settings.paths_per_iteration == 0 && s.features.has(device::Feature::GUIDING))
    cap = std::min<uint64_t>(cap, BakePolicy::learning_batch(covered));
  else if (settings.paths_per_iteration == 0 && s.features.has(device::Feature::RADIANCE_CACHE))
    s.grow_batches = true;
  s.capacity = static_cast<size_t>(std::clamp<uint64_t>(cap, 1, kSlotMask));

  cl::LuxBakeParams& p = s.params;
  p.width = static_cast<uint32_t>(s.atlas.width);
  p.height = static_cast<uint32_t>(s.atlas.height);
  p.texel_count = p.width * p.height;
  p.covered_count = static_cast<uint32_t>(covered);
  p.bake_seed = settings.seed;
  p.max_bounces = static_cast<uint32_t>(settings.max_bounces);
  p.rr_depth = static_cast<uint32_t>(settings.rr_depth);
  p.light_count = static_cast<uint32_t>(s.lights.lights.size());
  p.sky_light = s.lights.sky.light;
  p.clamp_luminance = settings.clamp_luminance;
  const Vec3 extent = s.soup.bounds.empty() ? Vec3{1, 1, 1} : s.soup.bounds.extent();
  const float largest = std::max({extent.x, extent.y, extent.z});
  p.offset_scale = std::clamp(largest, 1e-6f, 1.0f);
  p.capacity = static_cast<uint32_t>(s.capacity);
  p.encoding_count = static_cast<uint32_t>(s.plan.table.size());
  p.basis_stride = s.plan.stride;
  p.acceleration = settings.encodings.acceleration;
  p.has_reference = settings.reference ? 1u : 0u;
  p.shard_index = settings.sharded() ? settings.shard_index : 0u;
  p.shard_count = settings.sharded() ? settings.shard_count : 1u;
  return s;
}

}  // namespace luxel::pipeline
