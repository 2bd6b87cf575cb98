// Output assembly: turns the accumulation state read back from the device
// (a BakeCheckpoint's buffers) into what a bake returns, the irradiance
// image with coverage alpha, samples and relative error per texel, and the
// coefficients of every directional encoding with its manifest entry.
#pragma once

#include <vector>

#include "bake/bake.h"
#include "bake/bake_setup.h"

namespace luxel::pipeline {

// Irradiance RGBA of covered slots [begin, begin + mean.size()) from their
// running means, written into the whole image `rgba` (sized here when
// empty); alpha = fraction of the texel's 64 sample positions that lie on
// geometry.
void fill_irradiance(const BakeSetup& setup, const std::vector<cl::float4>& mean, size_t begin,
                     std::vector<float>& rgba);
// Relative standard error of the texel means of covered slots [begin, begin +
// state.spp.size()) (BakeResult::rel_error; 0 below 2 samples or at zero
// luminance), written into the whole image `rel_error` (sized here when empty).
void fill_rel_error(const BakeSetup& setup, const BakeCheckpoint& state, size_t begin,
                    std::vector<float>& rel_error);

// The result in three steps, so a bake in tiles can write each tile's state
// as it finishes: begin_result sizes r's images (zero) and encodings;
// write_state writes the state of covered slots [begin, begin + n) (n =
// state.spp.size()) into them (irradiance, samples, rel_error,
// coefficients) and adds its nonfinite count; finish_result adds what the
// setup decided (atlas, coverage, features, manifest entries).
// cancel: polled between the images (hundreds of MB each at 2048^2 with
// directional encodings); a request ends it with cancelled_error.
Status begin_result(const BakeSetup& setup, BakeResult& r, CancelToken cancel = {});
void write_state(const BakeSetup& setup, const BakeCheckpoint& state, size_t begin, BakeResult& r);
void finish_result(const BakeSetup& setup, const BakeSettings& settings, BakeResult& r);
// All three for one state of every covered slot.
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
