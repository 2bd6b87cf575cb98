#include "settings/bake_settings.h"

#include <algorithm>
#include <cmath>

#include "common/hash.h"
#include "kernels/shared/shard.h"
#include "settings/probe_spec.h"
#include "settings/settings_schema.h"

namespace luxel::pipeline {

uint32_t BakeSettings::shard_samples() const {
  return cl::lux_shard_samples(samples_per_texel, shard_index, shard_count);
}

namespace {

// probe_positions_fnv1a has always been hashed from this offset basis, the
// standard one (kFnv1aBasis = 14695981039346656037) a digit short; the
// fingerprints of checkpointed probe bakes depend on it.
constexpr uint64_t kDescribeFnv1aBasis = 1469598103934665603ull;

// node[/element]:sx,sy,ox,oy@page, exact to the float (%.9g). Placements
// are a list of records outside the schema (settings_schema.h).
std::string describe_placements(const std::vector<NodePlacement>& placements) {
  std::string list;
  for (const NodePlacement& p : placements) {
    if (!list.empty()) list += ' ';
    list += std::to_string(p.node);
    if (p.element >= 0) list += "/" + std::to_string(p.element);
    list += strprintf(":%.9g,%.9g,%.9g,%.9g@%d", p.scale_offset[0], p.scale_offset[1],
                      p.scale_offset[2], p.scale_offset[3], p.page);
  }
  return list;
}

}  // namespace

// One entry per setting of the schema, as its describe fields say
// (settings_schema.h), and the placements.
std::map<std::string, std::string> BakeSettings::describe() const {
  std::map<std::string, std::string> m;
  for (const Setting& st : settings_schema()) {
    if (st.described == Described::kNever || !st.is_active(*this)) continue;
    if (st.describe_when && !st.describe_when(*this)) continue;
    const SettingValue v = st.get(*this);
    if (st.described == Described::kUnlessDefault && same_setting_value(st, v, st.default_value))
      continue;
    std::string text = st.describe_text ? st.describe_text(*this) : describe_setting_value(st, v);
    if (st.describe_fnv1a)
      text =
          strprintf("%016llx", static_cast<unsigned long long>(fnv1a64(text, kDescribeFnv1aBasis)));
    m[st.describe_key ? st.describe_key : st.name] = std::move(text);
  }
  if (!node_placements.empty()) m["placements"] = describe_placements(node_placements);
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
  if (s.atlas.resolution > s.atlas.resolution_limit)
    return bad("resolution", strprintf("%d exceeds %s=%d", s.atlas.resolution, resolution_limit,
                                       s.atlas.resolution_limit));
  if (s.atlas.resolution == 0 && s.atlas.max_resolution > s.atlas.resolution_limit)
    return bad("max_resolution", strprintf("%d exceeds %s=%d", s.atlas.max_resolution,
                                           resolution_limit, s.atlas.resolution_limit));
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
  // Guiding draws the first direction from a learned mixture and weights it
  // by its density; the directional encodings' moments assume directions
  // uniform over the hemisphere with weight 1 (kernels/bake/guiding.h).
  if (s.guiding && !s.encodings.names.empty()) {
    auto plan = plan_encodings(s.encodings);
    if (plan && !plan.value().empty())
      return bad("guiding",
                 "first-bounce guiding is for irradiance lightmaps: the directional encodings "
                 "of settings.encodings need first directions uniform over the hemisphere; "
                 "leave guiding off or bake irradiance only");
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
