// Importance sampling of an image sky that knows the receiver's normal.
//
// Sampling the sky by radiance alone wastes every sample that falls below the
// receiver's horizon: about half of them for a uniform sky, more for a bright
// sky seen by a wall. The integrand of irradiance is L(w) max(0, n.w), so the
// best light sample follows that product. A full table per normal is out of
// reach, so sampling has two levels (the hierarchical split of Clarberg et
// al., "Wavelet Importance Sampling", SIGGRAPH 2005, in its simplest form):
//
//  1. Blocks of the image (at most 64 x 32) are chosen from a table of the
//     receiver's normal cell. Normals are grouped in the cells of an
//     octahedral map (Cigolle et al., "A Survey of Efficient Representations
//     for Independent Unit Vectors", JCGT 3(2), 2014, §3.1); a block's weight
//     is its radiance mass times the largest cosine any normal of the cell
//     can have with any direction of the block. That factor bounds the
//     cosine, so the density stays positive wherever some normal of the cell
//     sees light (the estimator stays unbiased), and blocks every such normal
//     sees from below get none.
//  2. A texel of the block is chosen by luminance x sin(theta) at full image
//     resolution (pbrt's Distribution2D restricted to the block), shared by
//     all normals, so small bright sources (the sun in an HDRI) keep their
//     full-resolution importance.
//
// The device side is in kernels/shading/lights.h (lux_sky_sample_st,
// lux_sky_pdf_st); the layout in kernels/shared/light.h (LuxSky).
#pragma once

#include <vector>

#include "common/math.h"
#include "kernels/shared/light.h"

namespace luxel::pipeline {

// The octahedral map the kernels use (lux_sky_normal_bin): the cell of unit
// local-frame normal n on a side x side grid, row-major.
int sky_normal_bin(Vec3 n, int side);
// The unit normal at the centre of cell `bin`.
Vec3 sky_normal_bin_centre(int bin, int side);

struct SkyDistributions {
  int blocks_x = 0, blocks_y = 0, block_width = 0, block_height = 0, normal_bins = 0;
  std::vector<float> block_cdfs;  // per normal cell (kernels/shared/light.h, LuxSky)
  std::vector<float> texel_cdfs;  // per block
};

// The distributions of an equirect image (rgb radiance, row 0 = up, the
// mapping of kernels/shared/light.h) in the sky's local frame, for
// normal_bins x normal_bins normal cells and at most max_blocks_x x
// max_blocks_y blocks. The image must have some light.
SkyDistributions build_sky_distributions(const std::vector<float>& rgb, int width, int height,
                                         int normal_bins = 16, int max_blocks_x = 64,
                                         int max_blocks_y = 32);

}  // namespace luxel::pipeline
