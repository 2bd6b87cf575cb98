#include "probes/probe_bake.h"

#include <cmath>

namespace luxel::probes {

const float* ProbeBake::sh(size_t probe) const {
  return &bake.encodings[0].coefficients[probe * static_cast<size_t>(sh_count) * 3];
}

double negative_irradiance_fraction(const ProbeBake& b, const std::array<float, 3>& sigma) {
  constexpr int kNormals = 256;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  size_t negative = 0, total = 0;
  for (size_t p = 0; p < b.count(); ++p) {
    for (int i = 0; i < kNormals; ++i) {
      const double z = 1.0 - (2.0 * i + 1.0) / kNormals, r = std::sqrt(1.0 - z * z);
      float e[3];
      sh_irradiance(b.sh(p), b.sh_count, sigma, float(r * std::cos(golden * i)),
                    float(r * std::sin(golden * i)), float(z), e);
      ++total;
      if (e[0] < 0 || e[1] < 0 || e[2] < 0) ++negative;
    }
  }
  return total ? double(negative) / double(total) : 0.0;
}

Result<ProbeBake> bake_probe_layout(const scene::Scene& scene,
                                    const pipeline::BakeSettings& settings,
                                    const ProbeBakeSettings& probe, ProbeLayout layout,
                                    device::Context& ctx, const pipeline::BakeHooks& hooks) {
  if (probe.basis != "sh1" && probe.basis != "sh2")
    return invalid_argument("settings.probe_basis: '" + probe.basis + "' is not sh1 or sh2");
  pipeline::BakeSettings st = settings;
  st.encodings.names = {probe.basis};
  st.filter = pipeline::Filter::kBox;
  st.adaptive = false;
  st.denoise = pipeline::Denoise::kOff;
  st.reference = nullptr;
  // The probe domain has no lightmap: its size and the job's probe
  // settings play no part (a stand-in keeps validate_settings content).
  if (st.atlas.resolution == 0 && !(st.atlas.texel_density > 0)) st.atlas.resolution = 1;
  st.probes.clear();
  st.lightmap = true;
  pipeline::ProbeDomain domain{layout.positions, layout.max_distance};
  auto r = pipeline::bake_probe_domain(scene, st, domain, ctx, hooks);
  if (!r) return r.status();
  ProbeBake out;
  out.layout = std::move(layout);
  out.bake = std::move(r.value());
  out.sh_count = probe.basis == "sh1" ? 4 : 9;
  out.window = probe.window;
  const float order = probe.basis == "sh1" ? 1.0f : 2.0f;
  out.sigma =
      sh_window_sigma(probe.window, probe.window_width > 0 ? probe.window_width : order + 1.0f);
  out.negative_raw = negative_irradiance_fraction(out, {1, 1, 1});
  out.negative_windowed = negative_irradiance_fraction(out, out.sigma);
  return out;
}

Result<ProbeBake> bake_probes(const scene::Scene& scene, const pipeline::BakeSettings& settings,
                              const ProbeBakeSettings& probe, device::Context& ctx,
                              const pipeline::BakeHooks& hooks) {
  auto layout = place_probes(scene, probe.placement);
  if (!layout) return layout.status();
  return bake_probe_layout(scene, settings, probe, std::move(layout.value()), ctx, hooks);
}

}  // namespace luxel::probes
