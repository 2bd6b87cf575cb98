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
// encodings from the state, and what the setup decided (atlas, coverage,
// compiled features of the bake and the tracer, sample-info size).
void assemble_result(const BakeSetup& setup, const BakeSettings& settings,
                     const BakeCheckpoint& state, BakeResult& r);

// Progress statistics from accum_stats' per-work-group partials: the mean
// relative error over the covered texels, the minimum samples per texel and,
// with a reference, RMSE and relMSE.
void sum_stats(const std::vector<cl::LuxAccumStats>& partials, uint32_t covered, bool has_reference,
               BakeProgress& p);

// The final progress report's figures, and the device's timing table.
void record_final_progress(const BakeProgress& p, device::Context& ctx, BakeResult& r);

// The error series as checkpoints store it (ErrorSample fields flattened,
// series_stride per point), both ways.
std::vector<ErrorSample> series_from_checkpoint(const BakeCheckpoint& c);
void series_to_checkpoint(const std::vector<ErrorSample>& series, BakeCheckpoint& c);

}  // namespace luxel::pipeline
