// A float image in host memory: the unit every output writer works on.
//
// Layout: row-major, row 0 is the top row (texel centre v = (y + 0.5) / height
// in glTF UV space, where v = 0 is the top of the texture), channels
// interleaved. A lightmap image is RGBA: RGB is the baked value (unassociated:
// the mean over the covered part of the texel) and A is coverage, the fraction
// of the texel covered by geometry (0 = no geometry).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "common/status.h"

namespace luxel::output {

struct Image {
  int width = 0, height = 0, channels = 0;
  std::vector<float> pixels;  // width * height * channels floats

  size_t texel_count() const { return static_cast<size_t>(width) * static_cast<size_t>(height); }
  size_t index(int x, int y, int c) const {
    return (static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)) *
               static_cast<size_t>(channels) +
           static_cast<size_t>(c);
  }
  float& at(int x, int y, int c) { return pixels[index(x, y, c)]; }
  float at(int x, int y, int c) const { return pixels[index(x, y, c)]; }
};

// A width x height x channels image with every value set to `fill`.
Image make_image(int width, int height, int channels, float fill = 0.0f);

// OK when width and height are 1..65536 and channels 1..64; otherwise
// INVALID_ARGUMENT naming `what`. Checked before allocating for a file header.
Status check_shape(int width, int height, int channels, const std::string& what);

// OK when the image has a positive size, 1..64 channels and exactly
// width*height*channels pixels; otherwise INVALID_ARGUMENT naming `what`
// (typically the output path) and the inconsistency.
Status check_image(const Image& image, const std::string& what);

}  // namespace luxel::output
