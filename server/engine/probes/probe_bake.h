// A light-probe bake: placement (placement.h), then the wavefront bake over
// the probe domain (pipeline::bake_probe_domain), then what the probe files
// need: per probe its SH L1/L2 radiance coefficients, scalar irradiance with
// its relative standard error, DDGI visibility moments and flags.
#pragma once

#include <string>
#include <vector>

#include "bake/bake.h"
#include "device/context.h"
#include "probes/placement.h"
#include "probes/sh_window.h"

namespace luxel::probes {

struct ProbeBakeSettings {
  PlacementSettings placement;
  std::string basis = "sh2";  // "sh1" (L1, 4 coefficients) or "sh2" (L2, 9)
  // Ringing control recorded in the files and applied by the SDK.
  ShWindow window = ShWindow::kHanning;
  float window_width = 0;  // 0: order + 1
};

struct ProbeBake {
  ProbeLayout layout;
  pipeline::BakeResult bake;  // probes x 1 "texels"; encodings[0] = the SH coefficients
  int sh_count = 9;
  ShWindow window = ShWindow::kHanning;
  std::array<float, 3> sigma{1, 1, 1};
  // How often reconstructed irradiance goes negative (any channel), over
  // every probe and 256 spherical-Fibonacci normals: raw and windowed.
  double negative_raw = 0, negative_windowed = 0;

  size_t count() const { return layout.positions.size(); }
  const float* sh(size_t probe) const;  // sh_count x RGB, coefficient-major
};

// settings: the bake's (samples_per_texel = samples per probe, time,
// target error, bounces, lights, seed); its encodings are replaced by
// probe.basis, its filter by box. The probe domain's progress, snapshots and
// checkpoints go through `hooks` as for a lightmap.
Result<ProbeBake> bake_probes(const scene::Scene& scene, const pipeline::BakeSettings& settings,
                              const ProbeBakeSettings& probe, device::Context& ctx,
                              const pipeline::BakeHooks& hooks = {});

// The same for an already placed layout (resume: the layout is recomputed
// deterministically, or given by a caller).
Result<ProbeBake> bake_probe_layout(const scene::Scene& scene,
                                    const pipeline::BakeSettings& settings,
                                    const ProbeBakeSettings& probe, ProbeLayout layout,
                                    device::Context& ctx, const pipeline::BakeHooks& hooks = {});

// Fraction of (probe, normal) pairs with negative irradiance in some channel.
double negative_irradiance_fraction(const ProbeBake& b, const std::array<float, 3>& sigma);

}  // namespace luxel::probes
