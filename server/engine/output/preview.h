// 8-bit sRGB PNG previews of a lightmap, for people and for progressive
// snapshots streamed to clients. The display transform is in tone_map.h.
//
// Input: a 4-channel image (RGB + coverage alpha, see image.h), a 3-channel
// RGB image (taken as fully covered) or a 1-channel image (grey, fully
// covered). Output: RGBA PNG, unassociated alpha = 255 where coverage > 0 and
// 0 elsewhere, so a viewer shows the atlas layout; the RGB of uncovered texels
// (dilated padding, or black) is still stored under alpha 0.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "output/image.h"

namespace luxel::output {

struct PreviewOptions {
  // Exposure in EV (a factor 2^exposure). With auto_exposure it is a
  // compensation on top of the automatic scale; 0 means none.
  float exposure = 0;
  // Scale so the 95th percentile luminance of covered texels maps to 0.8 after
  // the tone curve (before the sRGB OETF): L95 * k = 4, since 4 / (1 + 4) = 0.8.
  // An image whose percentile is 0 (all black, nothing covered) uses k = 1.
  bool auto_exposure = true;
};

// The exposure scale k the preview of `image` uses (always finite and > 0).
double preview_exposure_scale(const Image& image, const PreviewOptions& options = {});

// Writes the full-size preview of `rgba` to `path` atomically (common/atomic_file.h).
// INVALID_ARGUMENT naming the path for a malformed image, an unsupported
// channel count or an unwritable destination.
Status write_png_preview(const std::string& path, const Image& rgba,
                         const PreviewOptions& options = {});

// The preview as PNG bytes in memory, box-filtered down so the longest side is
// max_side (aspect kept, each side at least 1 texel; never enlarged). The box
// filter averages RGB weighted by coverage, so uncovered texels do not darken
// chart borders; an output texel is covered when any of its sources is.
// The exposure is computed from the full-size image, so a small preview looks
// like the full one.
Result<std::vector<uint8_t>> encode_png_preview(const Image& rgba, int max_side,
                                                const PreviewOptions& options = {});

// The box-filtered RGBA image encode_png_preview tone-maps (exposed for tests
// and for callers that want float thumbnails).
Result<Image> downscale_box(const Image& rgba, int max_side);

}  // namespace luxel::output
