#include "bake/progressive_variance.h"

#include <algorithm>
#include <cmath>

namespace luxel::pipeline {

double welford_variance(const BakeCheckpoint& state, size_t slot) {
  const double w = state.weight[slot].x, w2 = state.weight[slot].y;
  if (state.spp[slot] < 2 || !(w > 0)) return 0;
  const double var = std::max(0.0, double{state.m2[slot].w} / w);
  const double n_eff = w * w / std::max(w2, 1e-30);
  return var / n_eff;
}

bool ProgressiveVariance::due(double mean_spp) const {
  const double next = newer_.spp.empty() ? kFirstMilestone : 2 * newer_.mean_spp;
  return mean_spp >= next;
}

void ProgressiveVariance::record(const BakeCheckpoint& state, double mean_spp) {
  older_ = std::move(newer_);
  newer_ = Milestone{};
  newer_.mean_spp = mean_spp;
  newer_.spp = state.spp;
  newer_.luminance.resize(state.mean.size());
  for (size_t i = 0; i < state.mean.size(); ++i) newer_.luminance[i] = state.mean[i].w;
}

void ProgressiveVariance::reset() {
  older_ = Milestone{};
  newer_ = Milestone{};
}

double ProgressiveVariance::slot_variance(const BakeCheckpoint& state, size_t slot,
                                          bool* two_point) const {
  if (two_point) *two_point = false;
  const double n = state.spp[slot];
  // The milestone whose count is nearest n / 2 from below (and at least 2).
  const Milestone* best = nullptr;
  for (const Milestone* m : {&newer_, &older_}) {
    if (slot >= m->spp.size()) continue;
    const double s = m->spp[slot];
    if (s < 2 || s >= n) continue;
    if (!best || std::abs(s - 0.5 * n) < std::abs(best->spp[slot] - 0.5 * n)) best = m;
  }
  if (!best) return welford_variance(state, slot);
  if (two_point) *two_point = true;
  const double s = best->spp[slot];
  const double d = double{state.mean[slot].w} - double{best->luminance[slot]};
  return d * d * s / (n - s);
}

size_t ProgressiveVariance::fill(const BakeSetup& setup, const BakeCheckpoint& state, size_t begin,
                                 std::vector<float>& variance) const {
  const auto& covered = setup.info.covered_texels;
  variance.resize(size_t{setup.params.texel_count}, -1.0f);
  size_t two_point_slots = 0;
  for (size_t slot = 0; slot < state.spp.size(); ++slot) {
    bool two_point = false;
    const double v = slot_variance(state, slot, &two_point);
    if (!two_point) continue;
    variance[covered[begin + slot]] = static_cast<float>(v);
    ++two_point_slots;
  }
  return two_point_slots;
}

std::vector<float> ProgressiveVariance::overlay(std::vector<float> welford,
                                                const std::vector<float>& two_point) {
  for (size_t t = 0; t < welford.size() && t < two_point.size(); ++t)
    if (two_point[t] >= 0.0f) welford[t] = two_point[t];
  return welford;
}

}  // namespace luxel::pipeline
