#include "post/bake_seams.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>

#include "common/clock.h"

namespace luxel::pipeline {

void BakeSeamStitch::Totals::add(const output::SeamDiscontinuity& d) {
  const double n = static_cast<double>(d.points);
  points += d.points;
  sum_abs += d.rms_abs * d.rms_abs * n;
  sum_rel += d.rms_rel * d.rms_rel * n;
  max_abs = std::max(max_abs, d.max_abs);
  max_rel = std::max(max_rel, d.max_rel);
}

BakeSeamStitch::BakeSeamStitch(const BakeResult& result)
    : result_(result),
      encodings_before_(result.encodings.size()),
      encodings_after_(result.encodings.size()) {}

std::vector<output::StitchEdge> BakeSeamStitch::page_edges(int page) const {
  std::vector<output::StitchEdge> edges;
  for (const atlas::SeamEdge& e : result_.seams->edges)
    if (e.page == page) edges.push_back({e.a0, e.a1, e.b0, e.b1, e.chart_texels});
  return edges;
}

std::vector<float> BakeSeamStitch::page_rel_error(int page, size_t texels) const {
  const size_t first = size_t(page) * texels;
  if (result_.rel_error.size() < first + texels) return {};  // every gap is stitched
  return {result_.rel_error.begin() + ptrdiff_t(first),
          result_.rel_error.begin() + ptrdiff_t(first + texels)};
}

void BakeSeamStitch::stitch_page(int page, output::Image& irradiance, const output::Image& coverage,
                                 const std::vector<output::Image*>& encodings) {
  if (!enabled()) return;
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<output::StitchEdge> edges = page_edges(page);
  if (edges.empty()) return;
  const output::SeamStitcher stitcher(irradiance.width, irradiance.height, edges, coverage.pixels);
  narrow_chart_edges_ += stitcher.narrow_chart_edges();
  edges_ += edges.size() - stitcher.narrow_chart_edges();
  unknowns_ += stitcher.unknowns();
  before_.add(stitcher.measure(irradiance.pixels, 4, 0, 3));
  const std::vector<float> rel = page_rel_error(page, irradiance.texel_count());
  int it = stitcher.stitch(irradiance.pixels, 4, 0, 3, true, rel,  // irradiance >= 0
                           &structural_points_);
  after_.add(stitcher.measure(irradiance.pixels, 4, 0, 3));
  for (size_t k = 0; k < encodings.size() && k < encodings_before_.size(); ++k) {
    output::Image& img = *encodings[k];
    encodings_before_[k].add(stitcher.measure(img.pixels, img.channels, 0, img.channels));
    it = std::max(it, stitcher.stitch(img.pixels, img.channels, 0, img.channels, false, rel));
    encodings_after_[k].add(stitcher.measure(img.pixels, img.channels, 0, img.channels));
  }
  most_iterations_ = std::max(most_iterations_, it);
  seconds_ += seconds_since(t0);
}

void BakeSeamStitch::stitch_encoding(int page, size_t k, output::Image& img,
                                     const output::Image& coverage) {
  if (!enabled() || k >= encodings_before_.size()) return;
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<output::StitchEdge> edges = page_edges(page);
  if (edges.empty()) return;
  const output::SeamStitcher stitcher(img.width, img.height, edges, coverage.pixels);
  const std::vector<float> rel = page_rel_error(page, img.texel_count());
  encodings_before_[k].add(stitcher.measure(img.pixels, img.channels, 0, img.channels));
  most_iterations_ = std::max(
      most_iterations_, stitcher.stitch(img.pixels, img.channels, 0, img.channels, false, rel));
  encodings_after_[k].add(stitcher.measure(img.pixels, img.channels, 0, img.channels));
  seconds_ += seconds_since(t0);
}

void BakeSeamStitch::stitch_denoised_page(int page, output::Image& denoised,
                                          const output::Image& coverage) {
  if (!enabled()) return;
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<output::StitchEdge> edges = page_edges(page);
  if (edges.empty()) return;
  const output::SeamStitcher stitcher(denoised.width, denoised.height, edges, coverage.pixels);
  denoised_before_.add(stitcher.measure(denoised.pixels, 4, 0, 3));
  // The raw map's noise decides which gaps are structure here too (the
  // denoised map's own is smaller, so this errs towards stitching).
  const std::vector<float> rel = page_rel_error(page, denoised.texel_count());
  most_iterations_ =
      std::max(most_iterations_, stitcher.stitch(denoised.pixels, 4, 0, 3, true, rel));  // >= 0
  denoised_after_.add(stitcher.measure(denoised.pixels, 4, 0, 3));
  seconds_ += seconds_since(t0);
}

namespace {

nlohmann::json totals_json(size_t points, double sum_abs, double sum_rel, double max_abs,
                           double max_rel) {
  const double n = std::max<double>(1, double(points));
  return {{"rms_abs", std::sqrt(sum_abs / n)},
          {"max_abs", max_abs},
          {"rms_rel", std::sqrt(sum_rel / n)},
          {"max_rel", max_rel}};
}

}  // namespace

std::string BakeSeamStitch::manifest_json() const {
  if (!enabled()) return {};
  auto js = [](const Totals& t) {
    return totals_json(t.points, t.sum_abs, t.sum_rel, t.max_abs, t.max_rel);
  };
  const atlas::SeamSet& s = *result_.seams;
  const output::SeamStitchOptions o;
  nlohmann::json j = {{"stitched_edges", edges_},
                      {"cross_page_edges_skipped", s.cross_page},
                      {"non_manifold_edges_skipped", s.non_manifold},
                      {"hard_edges_skipped", s.hard_edges},
                      {"degenerate_edges_skipped", s.degenerate},
                      {"narrow_chart_edges_skipped", narrow_chart_edges_},
                      {"min_chart_texels", o.min_chart_texels},
                      {"max_move_sigmas", o.max_move_sigmas},
                      {"pool_move_sigmas", o.pool_move_sigmas},
                      {"structure_sigmas", o.structure_sigmas},
                      {"structure_rel_gap", o.structure_rel_gap},
                      {"structural_points_skipped", structural_points_},
                      {"sample_points", before_.points},
                      {"texels_solved", unknowns_},
                      {"seam_weight", o.seam_weight},
                      {"padding_weight", o.padding_weight},
                      {"max_cg_iterations", most_iterations_},
                      {"find_seconds", result_.seam_find_s},
                      {"stitch_seconds", seconds_},
                      {"irradiance_before", js(before_)},
                      {"irradiance_after", js(after_)}};
  if (denoised_before_.points > 0) {
    j["irradiance_denoised_before"] = js(denoised_before_);
    j["irradiance_denoised_after"] = js(denoised_after_);
  }
  for (size_t k = 0; k < encodings_before_.size(); ++k) {
    j["encodings"].push_back({{"name", result_.encodings[k].name},
                              {"before", js(encodings_before_[k])},
                              {"after", js(encodings_after_[k])}});
  }
  return j.dump();
}

}  // namespace luxel::pipeline
