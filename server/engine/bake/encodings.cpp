#include "bake/encodings.h"

#include <cmath>
#include <nlohmann/json.hpp>
#include <set>

#include "settings/bake_settings.h"
#include "settings/settings_schema.h"

namespace luxel::pipeline {

Result<std::vector<std::string>> parse_encoding_list(const std::string& list) {
  std::vector<std::string> names;
  size_t start = 0;
  while (start <= list.size()) {
    size_t end = list.find(',', start);
    if (end == std::string::npos) end = list.size();
    std::string item = list.substr(start, end - start);
    start = end + 1;
    if (item.empty() || item == "irradiance") continue;
    if (!encode::SphericalBasis::from_name(item))
      return invalid_argument(strprintf(
          "unknown encoding '%s': expected irradiance, sh1, sh2, sg6/sg9/sg12 (optionally -hemi), "
          "ambient-dice9 or ambient-dice12",
          item.c_str()));
    names.push_back(item);
  }
  return names;
}

Status validate_encodings(const EncodingSettings& e) {
  // The rules are the settings schema's (encodings, sg_sharpness, acceleration).
  BakeSettings s;
  s.encodings = e;
  for (const char* name : {"sg_sharpness", "encodings", "acceleration"}) {
    const Setting* st = find_setting(name);
    LUXEL_RETURN_IF_ERROR(check_setting(*st, st->get(s)));
  }
  for (const auto& n : e.names) {
    auto b = encode::SphericalBasis::from_name(n, e.sg_sharpness);
    if (!b) return invalid_argument("settings.encodings: " + b.status().message());
  }
  return Status::ok();
}

std::string Encoding::describe_json(const std::string& file, float acceleration,
                                    double residual_rms) const {
  nlohmann::ordered_json j = nlohmann::ordered_json::parse(basis.describe().to_json());
  j["frame"] =
      tangent_frame
          ? "tangent: z = interpolated shading normal, x = surface direction of "
            "increasing lightmap u (TEXCOORD_1) projected onto the tangent plane, y = z x x"
          : "world (glTF scene space, +y up)";
  j["solver"] = choice_name(solver);
  if (solver != EncodingSolver::kProjection) j["acceleration"] = acceleration;
  j["quantity"] =
      "incident radiance L(w) in W/(m^2 sr); reconstructed irradiance is in W/m^2 "
      "like irradiance.exr";
  if (residual_rms >= 0)
    j["residual_rms"] =
        residual_rms;  // mean over covered texels of the running RMS of delta (luminance)
  j["file"] = file;
  j["channels"] =
      strprintf("c00.R .. c%02d.B: coefficient i of each colour channel", basis.size() - 1);
  return j.dump();
}

Result<EncodingPlan> plan_encodings(const EncodingSettings& settings) {
  LUXEL_RETURN_IF_ERROR(validate_encodings(settings));
  EncodingPlan plan;
  for (const auto& name : settings.names) {
    auto named = encode::SphericalBasis::from_name(name, settings.sg_sharpness);
    if (!named) return named.status();
    encode::BasisSpec spec = named.value().spec();
    const bool hemisphere =
        (spec.kind == encode::BasisKind::kAmbientDice && spec.lobe_count == 9) ||
        (spec.kind == encode::BasisKind::kSphericalGaussian &&
         spec.lobe_layout == encode::BasisDomain::kHemisphere);
    spec.fit_domain = hemisphere ? encode::BasisDomain::kHemisphere : encode::BasisDomain::kSphere;
    auto basis = encode::SphericalBasis::create(spec);
    if (!basis) return basis.status();
    const bool sh = spec.kind == encode::BasisKind::kShL1 || spec.kind == encode::BasisKind::kShL2;
    EncodingSolver solver = settings.solver;
    if (solver == EncodingSolver::kAuto)
      solver = sh ? EncodingSolver::kProjection : EncodingSolver::kProgressiveNonNegative;

    cl::LuxEncoding e{};
    e.kind = sh ? LUX_ENC_SH
                : (spec.kind == encode::BasisKind::kSphericalGaussian ? LUX_ENC_SG : LUX_ENC_AD);
    e.count = basis.value().size();
    e.first_dir = static_cast<int>(plan.directions.size());
    e.state_offset = static_cast<int>(plan.stride);
    e.tangent_frame = hemisphere ? 1 : 0;
    e.hemisphere_fit = hemisphere ? 1 : 0;
    e.solver = solver == EncodingSolver::kProjection    ? LUX_SOLVER_PROJECTION
               : solver == EncodingSolver::kProgressive ? LUX_SOLVER_PROGRESSIVE
                                                        : LUX_SOLVER_PROGRESSIVE_NN;
    e.sharpness = spec.sharpness;
    for (const Vec3& d : basis.value().directions())
      plan.directions.push_back({d.x, d.y, d.z, 0.0f});
    plan.stride += static_cast<uint32_t>(1 + e.count);
    plan.table.push_back(e);
    plan.encodings.push_back({std::move(basis.value()), solver, hemisphere});
  }
  return plan;
}

void extract_coefficients(const EncodingPlan& plan, size_t k, const std::vector<cl::float4>& state,
                          const uint32_t* texels, size_t n, std::vector<float>& out) {
  const cl::LuxEncoding& e = plan.table[k];
  const size_t count = static_cast<size_t>(e.count);
  if (state.size() < n * plan.stride) return;
  for (size_t slot = 0; slot < n; ++slot) {
    const cl::float4* lobes = &state[slot * plan.stride + static_cast<size_t>(e.state_offset) + 1];
    float* px = &out[size_t{texels[slot]} * count * 3];
    for (size_t i = 0; i < count; ++i) {
      px[i * 3 + 0] = lobes[i].x;
      px[i * 3 + 1] = lobes[i].y;
      px[i * 3 + 2] = lobes[i].z;
    }
  }
}

}  // namespace luxel::pipeline
