// Output assembly: turns the accumulation state read back from the device
// (a BakeCheckpoint's buffers) into what a bake returns, the irradiance
// image with coverage alpha, samples and relative error per texel, and the
// coefficients of every directional encoding with its manifest entry.
#pragma once

#include <vector>

#include "pipeline/bake.h"
#include "pipeline/bake_setup.h"

namespace luxel::pipeline {

// Irradiance RGBA from the running means; alpha = fraction of the texel's
// 64 sample positions that lie on geometry.
void fill_irradiance(const BakeSetup& setup, const std::vector<cl::float4>& mean,
                     std::vector<float>& rgba);

// Fills r's images (irradiance, samples, rel_error), nonfinite count and
// encodings from the state.
void assemble_result(const BakeSetup& setup, const BakeSettings& settings,
                     const BakeCheckpoint& state, BakeResult& r);

}  // namespace luxel::pipeline
