/* Light probes (probe domain of the bake): constants and the direction
 * binning of the per-probe visibility, shared by the kernels, the host and
 * the SDK's reader (client/sdk/luxel_lightmap.h repeats the mapping; the
 * probe file records LUX_PROBE_VIS_SIDE). Compiled as OpenCL C and as C++.
 *
 * Visibility follows DDGI (Majercik et al. 2019, the irradiance-probe
 * article of support document 000): per probe and direction bin, the mean
 * and mean square of the distance to the first hit along the probe's
 * sample directions; a miss counts as the probe's maximum distance. The
 * bins are the cells of an octahedral map (Cigolle et al., JCGT 3(2) 2014)
 * of LUX_PROBE_VIS_SIDE^2 cells, z up. Each bin's state is one float4:
 * (mean t, mean t^2, samples, 0). */
#ifndef LUXEL_SHARED_PROBE_H
#define LUXEL_SHARED_PROBE_H

#include "shared/compat.h"

#ifndef LUX_DEVICE
#include <cmath>
namespace luxel::cl {
#endif

#define LUX_PROBE_VIS_SIDE 16
#define LUX_PROBE_VIS_BINS (LUX_PROBE_VIS_SIDE * LUX_PROBE_VIS_SIDE)

/* The octahedral cell (row-major, side x side) of unit direction (x, y, z). */
LUX_INLINE uint lux_probe_vis_bin(float x, float y, float z, int side) {
#ifdef LUX_DEVICE
  const float l1 = fabs(x) + fabs(y) + fabs(z);
#else
  const float l1 = std::fabs(x) + std::fabs(y) + std::fabs(z);
#endif
  float px = l1 > 0.0f ? x / l1 : 0.0f, py = l1 > 0.0f ? y / l1 : 0.0f;
  if (z < 0.0f) {
    const float ax = px < 0.0f ? -px : px, ay = py < 0.0f ? -py : py;
    const float qx = (1.0f - ay) * (px >= 0.0f ? 1.0f : -1.0f);
    const float qy = (1.0f - ax) * (py >= 0.0f ? 1.0f : -1.0f);
    px = qx;
    py = qy;
  }
  int ix = (int)((px * 0.5f + 0.5f) * (float)side), iy = (int)((py * 0.5f + 0.5f) * (float)side);
  ix = ix < 0 ? 0 : (ix > side - 1 ? side - 1 : ix);
  iy = iy < 0 ? 0 : (iy > side - 1 ? side - 1 : iy);
  return (uint)(iy * side + ix);
}

#ifndef LUX_DEVICE
}  // namespace luxel::cl
#endif

#endif /* LUXEL_SHARED_PROBE_H */
