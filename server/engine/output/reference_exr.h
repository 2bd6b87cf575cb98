// The reference lightmap of benchmark mode (BakeSettings::reference), read
// from an OpenEXR file. The local bake (`luxel bake --local --reference`) and
// the daemon (`reference_bake_id`) load it through this one function, with
// one rule for what is accepted.
#pragma once

#include <string>

#include "output/image.h"

namespace luxel::output {

// Reads `path` (read_exr) and returns it as RGBA float (channels == 4).
// Accepts 3 channels (RGB; alpha becomes 1) or 4 (RGBA, alpha kept). With
// expected_width/expected_height > 0 the image must have that size (the
// caller knows the lightmap's); with 0 the size is left to the bake, which
// refuses a reference of another size.
// Errors name the file: the read_exr codes for an unreadable file,
// INVALID_ARGUMENT for another channel count or a size mismatch.
Result<Image> read_reference_exr(const std::string& path, int expected_width = 0,
                                 int expected_height = 0);

}  // namespace luxel::output
