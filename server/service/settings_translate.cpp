#include "service/settings_translate.h"

#include <cmath>

#include "common/hash.h"

namespace luxel::service {
namespace {

Status bad(const char* field, const std::string& why) {
  return invalid_argument(strprintf("settings.%s: %s", field, why.c_str()));
}

Status read_vec3(const google::protobuf::RepeatedField<float>& v, const char* field, Vec3* out) {
  if (v.size() != 3) return bad(field, strprintf("expected 3 values, got %d", v.size()));
  for (float x : v)
    if (!std::isfinite(x)) return bad(field, "values must be finite");
  *out = Vec3{v[0], v[1], v[2]};
  return Status::ok();
}

bool finite_nonneg(double x) { return std::isfinite(x) && x >= 0; }

}  // namespace

Result<pipeline::BakeSettings> to_engine_settings(const v1::BakeSettings& in,
                                                  const SettingsLimits& limits,
                                                  ServiceBakeOptions* options) {
  pipeline::BakeSettings s;
  s.atlas.max_resolution = limits.max_resolution;
  if (in.resolution() > static_cast<uint32_t>(limits.max_resolution))
    return bad("resolution", strprintf("%u exceeds the daemon's limit --max-resolution=%d",
                                       in.resolution(), limits.max_resolution));
  if (!std::isfinite(in.texel_density()) || in.texel_density() < 0)
    return bad("texel_density", strprintf("must be >= 0, got %g", double(in.texel_density())));
  s.atlas.resolution = static_cast<int>(in.resolution());
  s.atlas.texel_density = in.resolution() == 0 ? in.texel_density() : 0.0f;
  if (in.resolution() == 0 && in.texel_density() == 0) s.atlas.resolution = std::min(512, limits.max_resolution);

  s.samples_per_texel = in.samples_per_texel();
  s.time_budget_s = in.time_budget_s();
  s.target_error = in.target_error();
  if (in.has_max_bounces()) {
    if (in.max_bounces() > 64) return bad("max_bounces", strprintf("must be in [0, 64], got %u", in.max_bounces()));
    s.max_bounces = static_cast<int>(in.max_bounces());
  }
  switch (in.filter()) {
    case v1::FILTER_UNSPECIFIED:
    case v1::FILTER_BOX: s.filter = pipeline::Filter::kBox; break;
    case v1::FILTER_GAUSSIAN: s.filter = pipeline::Filter::kGaussian; break;
    default: return bad("filter", strprintf("unknown filter %d", static_cast<int>(in.filter())));
  }
  switch (in.sky().kind()) {
    case v1::Sky::KIND_NONE: break;
    case v1::Sky::KIND_CONSTANT: {
      auto& sky = s.lights.sky;
      sky.kind = pipeline::SkySettings::Kind::kConstant;
      LUXEL_RETURN_IF_ERROR(read_vec3(in.sky().color(), "sky.color", &sky.color));
      if (!finite_nonneg(in.sky().intensity()))
        return bad("sky.intensity", strprintf("must be >= 0, got %g", double(in.sky().intensity())));
      sky.intensity = in.sky().intensity() == 0 ? 1.0f : in.sky().intensity();
      break;
    }
    default: return bad("sky.kind", strprintf("unknown sky kind %d", static_cast<int>(in.sky().kind())));
  }
  if (!finite_nonneg(in.sun().illuminance()))
    return bad("sun.illuminance", strprintf("must be >= 0, got %g", double(in.sun().illuminance())));
  if (in.sun().illuminance() > 0) {
    auto& sun = s.lights.sun;
    sun.enabled = true;
    sun.illuminance = in.sun().illuminance();
    LUXEL_RETURN_IF_ERROR(read_vec3(in.sun().direction(), "sun.direction", &sun.direction));
    if (sun.direction.x == 0 && sun.direction.y == 0 && sun.direction.z == 0)
      return bad("sun.direction", "must not be zero");
    if (in.sun().color_size() > 0) LUXEL_RETURN_IF_ERROR(read_vec3(in.sun().color(), "sun.color", &sun.color));
    const float r = in.sun().angular_radius_degrees();
    if (!std::isfinite(r) || r < 0 || r > 45)
      return bad("sun.angular_radius_degrees", strprintf("must be in [0, 45], got %g", double(r)));
    sun.angular_radius_degrees = r;
  }
  s.seed = in.seed() == 0 ? 1 : in.seed();
  if (in.paths_per_iteration() != 0) s.paths_per_iteration = in.paths_per_iteration();
  if (!in.encoding().empty()) {
    auto names = pipeline::parse_encoding_list(in.encoding());
    if (!names) return bad("encoding", names.status().message());
    s.encodings.names = names.value();
  }
  if (in.sg_sharpness() != 0) s.encodings.sg_sharpness = in.sg_sharpness();
  if (!in.solver().empty()) {
    auto solver = pipeline::parse_solver(in.solver());
    if (!solver) return bad("solver", solver.status().message());
    s.encodings.solver = solver.value();
  }
  if (in.acceleration() != 0) s.encodings.acceleration = in.acceleration();
  if (!in.reference_bake_id().empty()) {
    // The pixels are loaded by the runner (it has the bake store); an empty
    // placeholder keeps validation of target_metric meaningful here.
    s.reference = std::make_shared<const std::vector<float>>();
    s.reference_name = "bake " + in.reference_bake_id();
  }
  if (!in.target_metric().empty()) {
    auto metric = pipeline::parse_error_metric(in.target_metric());
    if (!metric) return bad("target_metric", metric.status().message());
    s.target_metric = metric.value();
  }
  if (in.dilation_texels() != 0) {
    if (in.dilation_texels() > 64)
      return bad("dilation_texels", strprintf("must be in [0, 64], got %u", in.dilation_texels()));
    s.dilation_texels = static_cast<int>(in.dilation_texels());
  }
  if (!finite_nonneg(in.progress_interval_s()))
    return bad("progress_interval_s", strprintf("must be >= 0, got %g", in.progress_interval_s()));
  if (in.progress_interval_s() > 0) s.progress_interval_s = std::max(0.05, in.progress_interval_s());

  ServiceBakeOptions opt;
  if (!finite_nonneg(in.snapshot_interval_s()))
    return bad("snapshot_interval_s", strprintf("must be >= 0, got %g", in.snapshot_interval_s()));
  if (in.snapshot_interval_s() > 0) opt.snapshot_interval_s = std::max(0.05, in.snapshot_interval_s());
  switch (in.snapshot_format()) {
    case v1::SNAPSHOT_FORMAT_UNSPECIFIED:
    case v1::SNAPSHOT_FORMAT_PNG: opt.snapshot_format = v1::SNAPSHOT_FORMAT_PNG; break;
    case v1::SNAPSHOT_FORMAT_EXR:
    case v1::SNAPSHOT_FORMAT_NONE: opt.snapshot_format = in.snapshot_format(); break;
    default:
      return bad("snapshot_format", strprintf("unknown format %d", static_cast<int>(in.snapshot_format())));
  }
  if (in.snapshot_max_side() > 8192)
    return bad("snapshot_max_side", strprintf("must be at most 8192, got %u", in.snapshot_max_side()));
  if (in.snapshot_max_side() != 0) opt.snapshot_max_side = static_cast<int>(in.snapshot_max_side());
  if (options) *options = opt;

  LUXEL_RETURN_IF_ERROR(pipeline::validate_settings(s));
  return s;
}

v1::BakeProgress to_proto(const pipeline::BakeProgress& p) {
  v1::BakeProgress out;
  out.set_elapsed_s(p.elapsed_s);
  out.set_paths(p.paths);
  out.set_mean_spp(p.mean_spp);
  out.set_min_spp(p.min_spp);
  out.set_error(p.error);
  out.set_eta_s(p.eta_s);
  out.set_fraction(p.fraction);
  out.set_rmse(p.rmse);
  out.set_rel_mse(p.rel_mse);
  return out;
}

std::string bake_fingerprint(const std::string& scene_id, const pipeline::BakeSettings& settings) {
  Hasher h;
  h.add(scene_id);
  for (const auto& [key, value] : settings.describe()) {
    if (key == "progress_interval_s") continue;  // shapes reports, not the lightmap
    h.add(key).add("=").add(value).add("\n");
  }
  return h.hex();
}

}  // namespace luxel::service
