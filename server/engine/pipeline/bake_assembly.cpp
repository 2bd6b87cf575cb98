#include "pipeline/bake_assembly.h"

#include <algorithm>
#include <bit>
#include <cmath>

namespace luxel::pipeline {

void fill_irradiance(const BakeSetup& setup, const std::vector<cl::float4>& mean,
                     std::vector<float>& rgba) {
  const atlas::SampleInfo& info = setup.info;
  rgba.assign(size_t{setup.params.texel_count} * 4, 0.0f);
  for (uint32_t texel : info.covered_texels) {
    const uint32_t off = info.offsets[texel];
    const int valid = std::popcount(info.words[off]) + std::popcount(info.words[off + 1]);
    float* px = &rgba[size_t{texel} * 4];
    px[0] = mean[texel].x;
    px[1] = mean[texel].y;
    px[2] = mean[texel].z;
    px[3] = static_cast<float>(valid) / 64.0f;
  }
}

namespace {

void assemble_encodings(const BakeSetup& setup, const BakeSettings& settings,
                        const BakeCheckpoint& state, BakeResult& r) {
  const EncodingPlan& plan = setup.plan;
  const auto& covered = setup.info.covered_texels;
  r.basis_bytes_per_texel = plan.bytes_per_texel();
  for (size_t k = 0; k < plan.encodings.size(); ++k) {
    EncodedLightmap e;
    e.name = plan.encodings[k].name();
    e.count = plan.table[k].count;
    e.coefficients = extract_coefficients(plan, k, state.basis, setup.params.texel_count);
    double residual = 0;
    for (uint32_t texel : covered) {
      const size_t header = size_t{texel} * plan.stride + plan.table[k].state_offset;
      residual += std::sqrt(std::max(0.0f, state.basis[header].y));
    }
    const bool progressive = plan.table[k].solver != LUX_SOLVER_PROJECTION;
    e.residual_rms = progressive ? residual / std::max<size_t>(1, covered.size()) : -1.0;
    e.manifest_json = plan.encodings[k].describe_json(
        e.name + ".exr", settings.encodings.acceleration, progressive ? e.residual_rms : -1.0);
    r.encodings.push_back(std::move(e));
  }
}

}  // namespace

void assemble_result(const BakeSetup& setup, const BakeSettings& settings,
                     const BakeCheckpoint& state, BakeResult& r) {
  const size_t t = setup.params.texel_count;
  r.width = setup.atlas.width;
  r.height = setup.atlas.height;
  fill_irradiance(setup, state.mean, r.irradiance);
  r.samples.assign(t, 0.0f);
  r.rel_error.assign(t, 0.0f);
  for (uint32_t texel : setup.info.covered_texels) {
    r.samples[texel] = static_cast<float>(state.spp[texel]);
    const double w = state.weight[texel].x, w2 = state.weight[texel].y;
    if (state.spp[texel] >= 2 && w > 0 && state.mean[texel].w > 0) {
      const double var = std::max(0.0, double{state.m2[texel].w} / w);
      const double n_eff = w * w / std::max(w2, 1e-30);
      r.rel_error[texel] = static_cast<float>(std::sqrt(var / n_eff) / state.mean[texel].w);
    }
  }
  r.nonfinite_dropped = state.nonfinite;
  assemble_encodings(setup, settings, state, r);
  r.atlas = setup.atlas;
  r.covered_texels = setup.info.covered_texels.size();
  device::FeatureSet reported = setup.features;
  for (const auto& [name, value] : setup.tracer->features().values()) reported.set(name, value);
  r.features = reported.describe();
  r.intersector = accel::intersector_name(setup.tracer->kind());
  r.sample_info_bytes = setup.info.bytes();
}

void sum_stats(const std::vector<cl::LuxAccumStats>& partials, uint32_t covered, bool has_reference,
               BakeProgress& p) {
  double err = 0, sq = 0, rel = 0;
  uint32_t min_spp = 0xFFFFFFFFu;
  for (const auto& s : partials) {
    err += s.rel_error_sum;
    sq += s.reference.x;
    rel += s.reference.y;
    min_spp = std::min(min_spp, s.min_spp);
  }
  p.error = err / static_cast<double>(covered);
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
