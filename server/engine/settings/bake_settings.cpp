#include "settings/bake_settings.h"

#include <algorithm>
#include <cmath>

#include "kernels/shared/shard.h"
#include "settings/probe_spec.h"
#include "settings/settings_schema.h"

namespace luxel::pipeline {

uint32_t BakeSettings::shard_samples() const {
  return cl::lux_shard_samples(samples_per_texel, shard_index, shard_count);
}

std::map<std::string, std::string> BakeSettings::describe() const {
  std::map<std::string, std::string> m;
  m["resolution"] = std::to_string(atlas.resolution);
  m["texel_density"] = strprintf("%g", atlas.texel_density);
  m["samples_per_texel"] = std::to_string(samples_per_texel);
  // Not in a bake's fingerprint (service/settings_translate.cpp): every
  // shard of one bake shares it.
  if (sharded()) m["shard"] = strprintf("%u/%u", shard_index, shard_count);
  m["time_budget_s"] = strprintf("%g", time_budget_s);
  m["target_error"] = strprintf("%g", target_error);
  if (target_metric != ErrorMetric::kEstimate) m["target_metric"] = choice_name(target_metric);
  if (reference) m["reference"] = reference_name.empty() ? "given" : reference_name;
  m["max_bounces"] = std::to_string(max_bounces);
  m["rr_depth"] = std::to_string(rr_depth);
  m["paths_per_iteration"] = paths_per_iteration ? std::to_string(paths_per_iteration) : "auto";
  if (device_memory_budget_mib > 0)
    m["device_memory_budget_mib"] = strprintf("%g", device_memory_budget_mib);
  m["seed"] = std::to_string(seed);
  m["filter"] = choice_name(filter);
  // Only when not the default: bake fingerprints (checkpoint resume) and
  // manifests of default bakes stay what they were before the setting.
  if (direct != DirectLight::kAuto) m["direct"] = choice_name(direct);
  if (!probes.empty()) {
    m["probes"] = probes;
    m["probe_sh_order"] = std::to_string(probe_sh_order);
    m["probe_window"] = probe_window;
    if (!probe_positions.empty()) {
      // FNV-1a of the positions: fingerprints see a changed list.
      uint64_t h = 1469598103934665603ull;
      for (unsigned char c : probe_positions) h = (h ^ c) * 1099511628211ull;
      m["probe_positions_fnv1a"] = strprintf("%016llx", static_cast<unsigned long long>(h));
    }
  }
  if (!lightmap) m["lightmap"] = "off";
  m["intersector"] = choice_name(intersector);
  m["uv"] = choice_name(uv);
  if (!node_placements.empty()) {
    // node[/element]:sx,sy,ox,oy@page, exact to the float (%.9g).
    std::string list;
    for (const NodePlacement& p : node_placements) {
      if (!list.empty()) list += ' ';
      list += std::to_string(p.node);
      if (p.element >= 0) list += "/" + std::to_string(p.element);
      list += strprintf(":%.9g,%.9g,%.9g,%.9g@%d", p.scale_offset[0], p.scale_offset[1],
                        p.scale_offset[2], p.scale_offset[3], p.page);
    }
    m["placements"] = list;
  }
  m["clamp_luminance"] = strprintf("%g", clamp_luminance);
  m["adaptive"] = adaptive ? strprintf("on,min=%u", adaptive_min_samples) : "off";
  m["compaction"] = compaction ? "on" : "off";
  m["sort_directions"] = sort_directions ? "on" : "off";
  m["sequence"] = random_sequence ? "random" : "sobol";
  m["dilation_texels"] = std::to_string(dilation_texels);
  // Only when not the default (as direct): fingerprints of default bakes stay
  // what they were; the filter never changes what the bake accumulates.
  if (denoise != Denoise::kOff) m["denoise"] = choice_name(denoise);
  m["seam_stitch"] = seam_stitch ? "on" : "off";
  if (!encodings.names.empty()) {
    std::string list = "irradiance";
    for (const auto& n : encodings.names) list += "," + n;
    m["encodings"] = list;
    m["sg_sharpness"] = strprintf("%g", encodings.sg_sharpness);
    m["solver"] = choice_name(encodings.solver);
    m["acceleration"] = strprintf("%g", encodings.acceleration);
  }
  const auto& sky = lights.sky;
  switch (sky.kind) {
    case SkySettings::Kind::kNone:
      m["sky"] = "none";
      break;
    case SkySettings::Kind::kConstant:
      m["sky"] =
          strprintf("constant %g,%g,%g x %g", sky.color.x, sky.color.y, sky.color.z, sky.intensity);
      break;
    case SkySettings::Kind::kEquirect:
      m["sky"] = strprintf("equirect %s x %g rot %g", sky.equirect_path.c_str(), sky.intensity,
                           sky.rotation_degrees);
      break;
  }
  if (lights.sun.enabled) {
    const auto& s = lights.sun;
    m["sun"] = strprintf("dir %g,%g,%g E %g radius %g deg", s.direction.x, s.direction.y,
                         s.direction.z, s.illuminance, s.angular_radius_degrees);
  }
  return m;
}

Status validate_settings(const BakeSettings& s, const char* resolution_limit) {
  // Each setting's own rule, from the schema.
  for (const Setting& st : settings_schema())
    if (st.is_active(s)) LUXEL_RETURN_IF_ERROR(check_setting(st, st.get(s)));

  // Rules between settings.
  auto bad = [](const char* field, const std::string& why) {
    return invalid_argument(strprintf("settings.%s: %s", field, why.c_str()));
  };
  if (s.atlas.resolution > s.atlas.max_resolution)
    return bad("resolution", strprintf("%d exceeds %s=%d", s.atlas.resolution, resolution_limit,
                                       s.atlas.max_resolution));
  if (!std::isfinite(s.atlas.texel_density))
    return bad("texel_density", "does not fit a 32-bit float (at most 3.4e38)");
  if (s.atlas.resolution == 0 && !(s.atlas.texel_density > 0))
    return bad("resolution", "give a resolution or a positive texel density");
  if (s.samples_per_texel == 0 && !(s.time_budget_s > 0) && !(s.target_error > 0))
    return bad("samples_per_texel",
               "no stopping rule: set samples, a time budget or a target error");
  if (!s.probes.empty()) {
    auto spec = probes::parse_probe_spec(s.probes);
    if (!spec) return spec.status();
  }
  if (s.probe_window != "none" && s.probe_window != "hanning" && s.probe_window != "lanczos")
    return bad("probe_window",
               strprintf("'%s' is not one of none, hanning, lanczos", s.probe_window.c_str()));
  if (!s.lightmap && s.probes.empty())
    return bad("lightmap", "off bakes nothing without settings.probes");
  const bool has_reference = s.reference || !s.job.reference_bake_id.empty();
  if (s.target_metric != ErrorMetric::kEstimate && !has_reference)
    return bad("target_metric",
               strprintf("'%s' needs a reference lightmap", choice_name(s.target_metric)));
  // Products of settings that are each in range but overflow together
  // (3e38 x 10): caught here, at submit, not when the light table is built.
  auto product_finite = [](Vec3 c, float k) {
    for (float v : {c.x, c.y, c.z})
      if (!std::isfinite(static_cast<float>(v * k))) return false;
    return true;
  };
  const auto& sky = s.lights.sky;
  if (sky.kind != SkySettings::Kind::kNone && !product_finite(sky.color, sky.intensity))
    return bad("sky.intensity",
               strprintf("sky.color x sky.intensity overflows a float (%g x %g)",
                         std::max({sky.color.x, sky.color.y, sky.color.z}), sky.intensity));
  const auto& sun = s.lights.sun;
  if (sun.enabled && !product_finite(sun.color, sun.illuminance))
    return bad("sun.illuminance",
               strprintf("sun.color x sun.illuminance overflows a float (%g x %g)",
                         std::max({sun.color.x, sun.color.y, sun.color.z}), sun.illuminance));
  for (size_t i = 0; i < s.node_placements.size(); ++i) {
    const NodePlacement& np = s.node_placements[i];
    const std::string field = strprintf("placements[%zu]", i);
    if (np.node < 0) return bad(field.c_str(), "node must be a glTF node index >= 0");
    for (int k = 0; k < 4; ++k)
      if (!std::isfinite(np.scale_offset[k]) || (k < 2 && np.scale_offset[k] == 0))
        return bad((field + ".scale_offset").c_str(),
                   "must be 4 finite numbers [sx, sy, ox, oy] with non-zero scales");
    if (np.page < 0 || np.page >= 1024)
      return bad((field + ".page").c_str(), "must be in [0, 1024)");
    for (size_t j = 0; j < i; ++j)
      if (s.node_placements[j].node == np.node && s.node_placements[j].element == np.element)
        return bad(
            field.c_str(),
            strprintf("node %d%s is placed twice (also placements[%zu])", np.node,
                      np.element >= 0 ? strprintf(" instance %d", np.element).c_str() : "", j));
  }
  if (s.shard_index > 0 && s.shard_index >= std::max(s.shard_count, 1u))
    return bad("shard_index", strprintf("must be < shard_count (%u), got %u",
                                        std::max(s.shard_count, 1u), s.shard_index));
  if (s.sharded()) {
    // A shard without samples would read as "no sample rule"; the blocks of
    // LUX_SHARD_BLOCK indices bound how many shards S samples can feed.
    if (s.samples_per_texel > 0 && s.shard_samples() == 0)
      return bad("shard_count",
                 strprintf("samples_per_texel=%u in blocks of %u samples leaves shard %u of %u "
                           "without samples: use at most %u shards",
                           s.samples_per_texel, LUX_SHARD_BLOCK, s.shard_index, s.shard_count,
                           (s.samples_per_texel + LUX_SHARD_BLOCK - 1) / LUX_SHARD_BLOCK));
    // Adaptive sampling allocates by the shard's own error estimates, which
    // no merge can reproduce: shards sample uniformly.
    if (s.adaptive)
      return bad("adaptive",
                 "adaptive sampling cannot be merged across shards (each shard would allocate by "
                 "its own error); sharded bakes sample uniformly (adaptive=false)");
    // The Gaussian filter gathers a neighbour's paths only in iterations
    // where the texel has a path of its own (kernels/bake/accumulate.h), so
    // which samples a texel sees depends on how the shard's paths were
    // batched: the shards would not add up to the single bake.
    if (s.filter == Filter::kGaussian)
      return bad("filter",
                 "the gaussian filter's gathered samples depend on how each shard batches its "
                 "paths, so shards do not merge exactly; sharded bakes use filter=box");
    // Progressive least squares (Listing 7.1) is Gauss-Seidel state that
    // depends on the order of the samples; projection state is running
    // means, which merge exactly.
    if (!s.encodings.names.empty()) {
      auto plan = plan_encodings(s.encodings);
      if (plan) {
        for (const Encoding& e : plan.value().encodings)
          if (e.solver != EncodingSolver::kProjection)
            return bad("solver",
                       strprintf("encoding '%s' uses the %s solver, whose state depends on the "
                                 "order of the samples and cannot be merged across shards "
                                 "(use solver=projection, or shard_count<=1)",
                                 e.name().c_str(), choice_name(e.solver)));
      }
    }
  }
  if (s.reference) {
    for (float v : *s.reference)
      if (!std::isfinite(v)) return bad("reference", "contains a non-finite value");
  }
  return Status::ok();
}

}  // namespace luxel::pipeline
