#include "pipeline/bake_settings.h"

#include <cmath>

namespace luxel::pipeline {

const char* filter_name(Filter f) { return f == Filter::kGaussian ? "gaussian" : "box"; }

const char* error_metric_name(ErrorMetric m) {
  switch (m) {
    case ErrorMetric::kEstimate: return "estimate";
    case ErrorMetric::kRmse: return "rmse";
    case ErrorMetric::kRelMse: return "relmse";
  }
  return "?";
}

Result<ErrorMetric> parse_error_metric(const std::string& name) {
  for (auto m : {ErrorMetric::kEstimate, ErrorMetric::kRmse, ErrorMetric::kRelMse})
    if (name == error_metric_name(m)) return m;
  return invalid_argument(strprintf("unknown error metric '%s': expected estimate, rmse or relmse",
                                    name.c_str()));
}

std::map<std::string, std::string> BakeSettings::describe() const {
  std::map<std::string, std::string> m;
  m["resolution"] = std::to_string(atlas.resolution);
  m["texel_density"] = strprintf("%g", atlas.texel_density);
  m["samples_per_texel"] = std::to_string(samples_per_texel);
  m["time_budget_s"] = strprintf("%g", time_budget_s);
  m["target_error"] = strprintf("%g", target_error);
  if (target_metric != ErrorMetric::kEstimate) m["target_metric"] = error_metric_name(target_metric);
  if (reference) m["reference"] = reference_name.empty() ? "given" : reference_name;
  m["max_bounces"] = std::to_string(max_bounces);
  m["rr_depth"] = std::to_string(rr_depth);
  m["paths_per_iteration"] = std::to_string(paths_per_iteration);
  m["seed"] = std::to_string(seed);
  m["filter"] = filter_name(filter);
  m["clamp_luminance"] = strprintf("%g", clamp_luminance);
  m["compaction"] = compaction ? "on" : "off";
  m["sort_directions"] = sort_directions ? "on" : "off";
  m["sequence"] = random_sequence ? "random" : "sobol";
  m["dilation_texels"] = std::to_string(dilation_texels);
  if (!encodings.names.empty()) {
    std::string list = "irradiance";
    for (const auto& n : encodings.names) list += "," + n;
    m["encodings"] = list;
    m["sg_sharpness"] = strprintf("%g", encodings.sg_sharpness);
    m["solver"] = solver_name(encodings.solver);
    m["acceleration"] = strprintf("%g", encodings.acceleration);
  }
  const auto& sky = lights.sky;
  switch (sky.kind) {
    case SkySettings::Kind::kNone: m["sky"] = "none"; break;
    case SkySettings::Kind::kConstant:
      m["sky"] = strprintf("constant %g,%g,%g x %g", sky.color.x, sky.color.y, sky.color.z, sky.intensity);
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

Status validate_settings(const BakeSettings& s) {
  auto bad = [](const char* field, const std::string& why) {
    return invalid_argument(strprintf("settings.%s: %s", field, why.c_str()));
  };
  if (s.atlas.resolution < 0 || s.atlas.resolution > s.atlas.max_resolution)
    return bad("resolution", strprintf("must be in [1, %d], got %d", s.atlas.max_resolution,
                                       s.atlas.resolution));
  if (s.atlas.resolution == 0 && !(s.atlas.texel_density > 0 && std::isfinite(s.atlas.texel_density)))
    return bad("resolution", "give a resolution or a positive texel density");
  if (s.samples_per_texel == 0 && !(s.time_budget_s > 0) && !(s.target_error > 0))
    return bad("samples_per_texel", "no stopping rule: set samples, a time budget or a target error");
  if (!(s.time_budget_s >= 0) || !std::isfinite(s.time_budget_s))
    return bad("time_budget_s", strprintf("must be >= 0, got %g", s.time_budget_s));
  if (!(s.target_error >= 0) || !std::isfinite(s.target_error))
    return bad("target_error", strprintf("must be >= 0, got %g", s.target_error));
  if (s.target_metric != ErrorMetric::kEstimate && !s.reference)
    return bad("target_metric", strprintf("'%s' needs a reference lightmap", error_metric_name(s.target_metric)));
  if (s.reference) {
    for (float v : *s.reference)
      if (!std::isfinite(v)) return bad("reference", "contains a non-finite value");
  }
  if (s.max_bounces < 0 || s.max_bounces > 64)
    return bad("max_bounces", strprintf("must be in [0, 64], got %d", s.max_bounces));
  if (s.rr_depth < 1 || s.rr_depth > 64)
    return bad("rr_depth", strprintf("must be in [1, 64], got %d", s.rr_depth));
  if (s.paths_per_iteration < 1024 || s.paths_per_iteration > (1u << 26))
    return bad("paths_per_iteration", strprintf("must be in [1024, 2^26], got %u", s.paths_per_iteration));
  if (!(s.clamp_luminance >= 0) || !std::isfinite(s.clamp_luminance))
    return bad("clamp_luminance", strprintf("must be >= 0, got %g", s.clamp_luminance));
  if (!(s.progress_interval_s > 0))
    return bad("progress_interval_s", strprintf("must be > 0, got %g", s.progress_interval_s));
  if (s.dilation_texels < 0 || s.dilation_texels > 64)
    return bad("dilation_texels", strprintf("must be in [0, 64], got %d", s.dilation_texels));
  return validate_encodings(s.encodings);
}

}  // namespace luxel::pipeline
