#include "output/image.h"

namespace luxel::output {

Image make_image(int width, int height, int channels, float fill) {
  Image image{width, height, channels, {}};
  image.pixels.assign(image.texel_count() * static_cast<size_t>(channels), fill);
  return image;
}

Status check_shape(int width, int height, int channels, const std::string& what) {
  if (width <= 0 || height <= 0)
    return invalid_argument(
        strprintf("%s: image has zero size (%d x %d)", what.c_str(), width, height));
  // OpenEXR and PNG address rows and columns with int; this keeps texel
  // indices and byte counts far from overflow.
  if (width > (1 << 16) || height > (1 << 16))
    return invalid_argument(strprintf("%s: image %d x %d exceeds the 65536 texel side limit",
                                      what.c_str(), width, height));
  if (channels <= 0 || channels > 64)
    return invalid_argument(
        strprintf("%s: image has %d channels (1..64 allowed)", what.c_str(), channels));
  return Status::ok();
}

Status check_image(const Image& image, const std::string& what) {
  LUXEL_RETURN_IF_ERROR(check_shape(image.width, image.height, image.channels, what));
  const size_t expected = image.texel_count() * static_cast<size_t>(image.channels);
  if (image.pixels.size() != expected)
    return invalid_argument(strprintf("%s: image %d x %d x %d needs %zu floats but holds %zu",
                                      what.c_str(), image.width, image.height, image.channels,
                                      expected, image.pixels.size()));
  return Status::ok();
}

}  // namespace luxel::output
