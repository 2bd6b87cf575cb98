// Dilation (edge padding) of a lightmap: fills texels that no geometry covers
// with the values of nearby covered texels, so bilinear filtering and mip maps
// at chart borders do not blend in black. This is the "dilation filter that
// fills empty pixels with the blended contents of neighbouring filled pixels"
// of thesis section 6.4.1 (also named in section 3.2 as the common, approximate
// alternative to gather-based accumulation; section 4.1.2 explains why charts
// keep a texel margin that this padding then fills).
#pragma once

#include "output/image.h"

namespace luxel::output {

// Dilates a 4-channel lightmap in place. Coverage is the alpha channel
// (channel 3): a texel is covered when alpha > 0.
//
// Ring by ring, up to `radius` passes: each pass gives every still-empty
// texel that touches (8-neighbourhood) at least one filled texel the plain
// average of those filled neighbours, all computed from the state at the start
// of the pass (so the result does not depend on scan order). After pass r every
// empty texel within Chebyshev distance r of a covered texel is filled; texels
// further away keep their values.
//
// Covered texels never change, and alpha is never written: it keeps meaning
// "fraction of the texel covered by geometry" (0 for dilated texels), so a
// consumer can still tell baked texels from padding. Deterministic.
// INVALID_ARGUMENT for a malformed image, channels != 4, or radius < 0.
Status dilate(Image& rgba, int radius);

// The same for an image of any channel count whose coverage lives in a
// separate single-channel image of the same size (covered when > 0); every
// channel of `image` is dilated. For encodings with many coefficients
// (SH, SG) stored without an alpha channel.
Status dilate(Image& image, const Image& coverage, int radius);

}  // namespace luxel::output
