#include "output/reference_exr.h"

#include <utility>
#include <vector>

#include "output/exr.h"

namespace luxel::output {

Result<Image> read_reference_exr(const std::string& path, int expected_width, int expected_height) {
  auto image = read_exr(path);
  if (!image) return image.status();
  const Image& in = image.value();
  if (in.channels != 3 && in.channels != 4)
    return invalid_argument(
        strprintf("reference lightmap '%s': %d channels, expected 3 (RGB) or 4 (RGBA)",
                  path.c_str(), in.channels));
  if ((expected_width > 0 || expected_height > 0) &&
      (in.width != expected_width || in.height != expected_height))
    return invalid_argument(
        strprintf("reference lightmap '%s': %dx%d texels, the lightmap is %dx%d", path.c_str(),
                  in.width, in.height, expected_width, expected_height));
  if (in.channels == 4) return image;
  Image rgba;
  rgba.width = in.width;
  rgba.height = in.height;
  rgba.channels = 4;
  rgba.pixels.assign(in.texel_count() * 4, 1.0f);
  for (size_t t = 0; t < in.texel_count(); ++t)
    for (size_t c = 0; c < 3; ++c) rgba.pixels[t * 4 + c] = in.pixels[t * 3 + c];
  return rgba;
}

}  // namespace luxel::output
