// Seam stitching of a bake's written images (output/seam_stitch.h on the
// seams atlas/seams.h found, BakeResult::seams), page by page, after
// dilation: a bilinear fetch along a seam sits on the chart's border and
// reads the padding texels that dilation fills, so those take part in the
// solve (with a small data weight) and are written as stitched. Dilation
// cannot undo it afterwards, because it runs first.
//
// Sample points whose two sides differ by more than the bake's own noise
// (BakeResult::rel_error) explains, and by more than half their mean, are
// discontinuities of the lighting and are not stitched
// (output::SeamStitchOptions::structure_sigmas).
//
// Seams whose two sides lie on different pages are left alone (counted in
// the manifest). The discontinuity figures are those of
// output::SeamDiscontinuity, over all pages' sample points.
#pragma once

#include <string>
#include <vector>

#include "bake/bake.h"
#include "output/image.h"
#include "output/seam_stitch.h"

namespace luxel::pipeline {

class BakeSeamStitch {
 public:
  // Does nothing when result.seams is null (seam_stitch off).
  explicit BakeSeamStitch(const BakeResult& result);

  bool enabled() const { return result_.seams != nullptr; }

  // Stitches page `page`'s dilated irradiance (RGB; alpha untouched) and
  // every encoding's coefficients in place; `coverage` is the page's alpha.
  void stitch_page(int page, output::Image& irradiance, const output::Image& coverage,
                   const std::vector<output::Image*>& encodings);

  // Encoding k of `page` alone (after stitch_page of the page's irradiance),
  // so output assembly holds one encoding's image at a time.
  void stitch_encoding(int page, size_t k, output::Image& image, const output::Image& coverage);

  // Stitches page `page`'s dilated denoised irradiance (RGB) the same way:
  // the denoiser filters within charts, so its two sides of a seam disagree
  // as the raw map's do.
  void stitch_denoised_page(int page, output::Image& denoised, const output::Image& coverage);

  // The manifest's "seam_stitch" object; empty when not enabled.
  std::string manifest_json() const;

 private:
  // Sums for RMS and maxima of SeamDiscontinuity over pages.
  struct Totals {
    size_t points = 0;
    double sum_abs = 0, sum_rel = 0, max_abs = 0, max_rel = 0;
    void add(const output::SeamDiscontinuity& d);
  };
  std::vector<output::StitchEdge> page_edges(int page) const;
  // The page's rows of the bake's relative standard error (the stitch's
  // noise, output::SeamStitchOptions::structure_sigmas); empty if the
  // result has none.
  std::vector<float> page_rel_error(int page, size_t texels) const;

  const BakeResult& result_;
  size_t edges_ = 0, narrow_chart_edges_ = 0, unknowns_ = 0;
  size_t structural_points_ = 0;  // irradiance sample points left out as structure
  int most_iterations_ = 0;
  double seconds_ = 0;
  Totals before_, after_, denoised_before_, denoised_after_;
  std::vector<Totals> encodings_before_, encodings_after_;
};

}  // namespace luxel::pipeline
