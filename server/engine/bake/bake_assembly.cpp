#include "bake/bake_assembly.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include "bake/host_memory.h"
#include "bake/progressive_variance.h"
#include "kernels/shared/probe.h"

namespace luxel::pipeline {

void fill_irradiance(const BakeSetup& setup, const std::vector<cl::float4>& mean, size_t begin,
                     std::vector<float>& rgba) {
  const atlas::SampleInfo& info = setup.info;
  rgba.resize(size_t{setup.params.texel_count} * 4, 0.0f);
  for (size_t slot = 0; slot < mean.size(); ++slot) {
    const uint32_t texel = info.covered_texels[begin + slot];
    const uint32_t off = info.offsets[texel];
    const int valid = std::popcount(info.words[off]) + std::popcount(info.words[off + 1]);
    float* px = &rgba[size_t{texel} * 4];
    px[0] = mean[slot].x;
    px[1] = mean[slot].y;
    px[2] = mean[slot].z;
    px[3] = static_cast<float>(valid) / 64.0f;
  }
}

Status begin_result(const BakeSetup& setup, BakeResult& r, CancelToken cancel) {
  const size_t t = setup.params.texel_count;
  r.width = setup.atlas.width;
  r.height = setup.atlas.height;
  // Sized with host_memory.h's figures, the submit-time estimate's.
  r.irradiance.assign(t * kIrradianceFloats, 0.0f);
  r.samples.assign(t * kScalarImageFloats, 0.0f);
  r.rel_error.assign(t * kScalarImageFloats, 0.0f);
  r.nonfinite_dropped = 0;
  r.encodings.clear();
  const EncodingPlan& plan = setup.plan;
  for (size_t k = 0; k < plan.encodings.size(); ++k) {
    LUXEL_RETURN_IF_ERROR(check_cancel(cancel, "the result's images"));
    EncodedLightmap e;
    e.name = plan.encodings[k].name();
    e.count = plan.table[k].count;
    e.coefficients.assign(t * coefficient_floats(plan, k), 0.0f);
    e.residual_rms = 0;  // the sum over covered texels until finish_result
    r.encodings.push_back(std::move(e));
  }
  return check_cancel(cancel, "the result's images");
}

void fill_rel_error(const BakeSetup& setup, const BakeCheckpoint& state, size_t begin,
                    std::vector<float>& rel_error) {
  const auto& covered = setup.info.covered_texels;
  rel_error.resize(size_t{setup.params.texel_count}, 0.0f);
  for (size_t slot = 0; slot < state.spp.size(); ++slot) {
    const uint32_t texel = covered[begin + slot];
    if (state.spp[slot] >= 2 && state.weight[slot].x > 0 && state.mean[slot].w > 0)
      rel_error[texel] =
          static_cast<float>(std::sqrt(welford_variance(state, slot)) / state.mean[slot].w);
  }
}

void write_state(const BakeSetup& setup, const BakeCheckpoint& state, size_t begin, BakeResult& r) {
  const auto& covered = setup.info.covered_texels;
  fill_irradiance(setup, state.mean, begin, r.irradiance);
  for (size_t slot = 0; slot < state.spp.size(); ++slot)
    r.samples[covered[begin + slot]] = static_cast<float>(state.spp[slot]);
  fill_rel_error(setup, state, begin, r.rel_error);
  r.nonfinite_dropped += state.nonfinite;
  const EncodingPlan& plan = setup.plan;
  if (!setup.probes.empty()) {
    // The visibility bins close each probe's record (bake_setup.cpp).
    constexpr size_t kBins = LUX_PROBE_VIS_BINS;
    r.probe_visibility.resize(setup.probes.size() * kBins * 4, 0.0f);
    for (size_t slot = 0; slot < state.spp.size(); ++slot) {
      const cl::float4* bins = &state.basis[(slot + 1) * plan.stride - kBins];
      float* out = &r.probe_visibility[covered[begin + slot] * kBins * 4];
      for (size_t b = 0; b < kBins; ++b) {
        out[b * 4 + 0] = bins[b].x;
        out[b * 4 + 1] = bins[b].y;
        out[b * 4 + 2] = bins[b].z;
        out[b * 4 + 3] = 0.0f;
      }
    }
  }
  for (size_t k = 0; k < plan.encodings.size(); ++k) {
    EncodedLightmap& e = r.encodings[k];
    extract_coefficients(plan, k, state.basis, covered.data() + begin, state.spp.size(),
                         e.coefficients);
    for (size_t slot = 0; slot < state.spp.size(); ++slot) {
      const size_t header = slot * plan.stride + plan.table[k].state_offset;
      e.residual_rms += std::sqrt(std::max(0.0f, state.basis[header].y));
    }
  }
}

void finish_result(const BakeSetup& setup, const BakeSettings& settings, BakeResult& r) {
  const EncodingPlan& plan = setup.plan;
  const size_t covered = setup.info.covered_texels.size();
  r.basis_bytes_per_texel = plan.bytes_per_texel();
  for (size_t k = 0; k < plan.encodings.size(); ++k) {
    EncodedLightmap& e = r.encodings[k];
    const bool progressive = plan.table[k].solver != LUX_SOLVER_PROJECTION;
    e.residual_rms = progressive ? e.residual_rms / std::max<size_t>(1, covered) : -1.0;
    e.manifest_json = plan.encodings[k].describe_json(
        e.name + ".exr", settings.encodings.acceleration, progressive ? e.residual_rms : -1.0);
  }
  r.atlas = setup.atlas;
  r.covered_texels = covered;
  r.features = device::FeatureSet(setup.features).merge(setup.tracer->features()).describe();
  r.intersector = choice_name(setup.tracer->kind());
  r.sample_info_bytes = setup.info.bytes();
}

void assemble_result(const BakeSetup& setup, const BakeSettings& settings,
                     const BakeCheckpoint& state, BakeResult& r) {
  (void)begin_result(setup, r);  // no cancel token: always OK
  write_state(setup, state, 0, r);
  finish_result(setup, settings, r);
}

void sum_stats(const std::vector<cl::LuxAccumStats>& partials, uint32_t covered, bool has_reference,
               BakeProgress& p) {
  double err = 0, coverage = 0, sq = 0, rel = 0;
  uint32_t min_spp = 0xFFFFFFFFu;
  for (const auto& s : partials) {
    err += s.rel_error_sum;
    coverage += s.coverage_sum;
    sq += s.reference.x;
    rel += s.reference.y;
    min_spp = std::min(min_spp, s.min_spp);
  }
  // The coverage-weighted mean (kernels/bake/stats.h); every covered texel
  // has a coverage of at least 1/64.
  p.error = coverage > 0 ? err / coverage : 0.0;
  if (has_reference) {
    p.rmse = std::sqrt(sq / covered);
    p.rel_mse = rel / covered;
  }
  p.min_spp = min_spp;
}

void record_final_progress(const BakeProgress& p, device::Context& ctx, BakeResult& r) {
  r.paths = p.paths;
  r.mean_spp = p.mean_spp;
  r.min_spp = p.min_spp;
  r.error = p.error;
  r.rmse = p.rmse;
  r.rel_mse = p.rel_mse;
  r.device = ctx.info().describe();
  r.kernel_table = ctx.timer().table();
  for (const auto& [name, stats] : ctx.timer().stats())
    r.kernel_ms.push_back({name, stats.total_ms});
}

std::vector<ErrorSample> series_from_checkpoint(const BakeCheckpoint& c) {
  std::vector<ErrorSample> out;
  const auto& s = c.series;
  const size_t stride = c.series_stride;
  for (size_t i = 0; i + stride <= s.size(); i += stride)
    out.push_back({s[i], static_cast<uint64_t>(s[i + 1]), s[i + 2], static_cast<uint32_t>(s[i + 3]),
                   s[i + 4], stride >= 7 ? s[i + 5] : -1.0, stride >= 7 ? s[i + 6] : -1.0});
  return out;
}

void series_to_checkpoint(const std::vector<ErrorSample>& series, BakeCheckpoint& c) {
  c.series_stride = 7;
  for (const auto& e : series)
    c.series.insert(c.series.end(), {e.elapsed_s, double(e.paths), e.mean_spp, double(e.min_spp),
                                     e.error, e.rmse, e.rel_mse});
}

}  // namespace luxel::pipeline
