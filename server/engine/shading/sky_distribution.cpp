#include "shading/sky_distribution.h"

#include <algorithm>
#include <cmath>

#include "common/dvec3.h"
#include "common/status.h"
#include "shading/cdf.h"
#include "shading/color.h"

namespace luxel::pipeline {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kHalfPi = 0.5 * kPi;

// Inverse of the octahedral map at (u, v) in [0, 1]^2 (y up, the (x, z)
// plane folded over the lower faces).
DVec3 octahedral_decode(double u, double v) {
  const double px = 2 * u - 1, pz = 2 * v - 1;
  DVec3 n{px, 1 - std::fabs(px) - std::fabs(pz), pz};
  if (n.y < 0) {
    n.x = (1 - std::fabs(pz)) * (px >= 0 ? 1 : -1);
    n.z = (1 - std::fabs(px)) * (pz >= 0 ? 1 : -1);
  }
  return normalize(n);
}

// Local direction at image coordinates (s, t) (kernels/shared/light.h).
DVec3 equirect_direction(double s, double t) {
  const double theta = kPi * t, phi = 2 * kPi * (s - 0.5);
  return {std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi)};
}

// Largest angle between the centre of a normal cell and any normal of it:
// a dense grid over the cell, edges included, plus a margin for the float
// arithmetic of the kernel's cell lookup.
double normal_cell_radius(int bin, int side, const DVec3& centre) {
  const int steps = 16;
  const int bx = bin % side, by = bin / side;
  double worst = 0;
  for (int i = 0; i <= steps; ++i)
    for (int j = 0; j <= steps; ++j) {
      const double u = (bx + double(j) / steps) / side, v = (by + double(i) / steps) / side;
      worst = std::max(worst, angle_between(centre, octahedral_decode(u, v)));
    }
  return worst * 1.01 + 1e-3;
}

// Largest angle between the centre of the (s, t) rectangle [s0, s1] x
// [t0, t1] and its corners and edge midpoints (the distance from the centre
// grows along each edge towards the corners).
double rectangle_radius(double s0, double s1, double t0, double t1, DVec3* centre) {
  *centre = equirect_direction(0.5 * (s0 + s1), 0.5 * (t0 + t1));
  double worst = 0;
  for (double s : {s0, 0.5 * (s0 + s1), s1})
    for (double t : {t0, 0.5 * (t0 + t1), t1})
      worst = std::max(worst, angle_between(*centre, equirect_direction(s, t)));
  return worst * 1.01 + 1e-4;
}

// Appends one 2D table: the marginal cdf over `rows` rows, then the
// conditional cdf of each row (weights row-major, rows x cols). An all-zero
// table is written as zeros: the device then reads pmf 0 for everything and
// draws no sample from it (lux_sample_cdf's pmf is 0).
void append_table(const std::vector<double>& weights, int rows, int cols, std::vector<float>* out) {
  std::vector<float> conditionals;
  conditionals.reserve(size_t(rows) * size_t(cols + 1));
  std::vector<double> row_totals(static_cast<size_t>(rows));
  double total = 0;
  for (int r = 0; r < rows; ++r) {
    row_totals[size_t(r)] =
        append_cdf(&weights[size_t(r) * size_t(cols)], size_t(cols), &conditionals);
    total += row_totals[size_t(r)];
  }
  if (!(total > 0)) {
    out->insert(out->end(), size_t(rows + 1) + conditionals.size(), 0.0f);
    return;
  }
  append_cdf(row_totals, out);
  out->insert(out->end(), conditionals.begin(), conditionals.end());
}

}  // namespace

int sky_normal_bin(Vec3 n, int side) {
  const double l1 = std::fabs(n.x) + std::fabs(n.y) + std::fabs(n.z);
  double px = l1 > 0 ? n.x / l1 : 0, pz = l1 > 0 ? n.z / l1 : 0;
  if (n.y < 0) {
    const double fx = (1 - std::fabs(pz)) * (px >= 0 ? 1 : -1);
    const double fz = (1 - std::fabs(px)) * (pz >= 0 ? 1 : -1);
    px = fx;
    pz = fz;
  }
  const int ix = std::clamp(int((px * 0.5 + 0.5) * side), 0, side - 1);
  const int iy = std::clamp(int((pz * 0.5 + 0.5) * side), 0, side - 1);
  return iy * side + ix;
}

Vec3 sky_normal_bin_centre(int bin, int side) {
  const DVec3 c = octahedral_decode((bin % side + 0.5) / side, (bin / side + 0.5) / side);
  return {float(c.x), float(c.y), float(c.z)};
}

SkyDistributions build_sky_distributions(const std::vector<float>& rgb, int width, int height,
                                         int normal_bins, int max_blocks_x, int max_blocks_y) {
  LUXEL_CHECK(width > 0 && height > 0 && rgb.size() == size_t(width) * size_t(height) * 3);
  LUXEL_CHECK(normal_bins > 0 && max_blocks_x > 0 && max_blocks_y > 0);
  SkyDistributions d;
  const int bw = (width + max_blocks_x - 1) / max_blocks_x;
  const int bh = (height + max_blocks_y - 1) / max_blocks_y;
  const int nbx = (width + bw - 1) / bw, nby = (height + bh - 1) / bh;
  d.block_width = bw;
  d.block_height = bh;
  d.blocks_x = nbx;
  d.blocks_y = nby;
  d.normal_bins = normal_bins;

  // Level 2: per block, its texels by luminance x sin(theta) (the solid
  // angle of a texel row is proportional to sin(theta) for equal (s, t)
  // area); texels past the image edge weigh 0.
  std::vector<double> mass(size_t(nbx) * size_t(nby), 0.0);
  std::vector<double> texel_weights(size_t(bw) * size_t(bh));
  for (int by = 0; by < nby; ++by)
    for (int bx = 0; bx < nbx; ++bx) {
      double sum = 0;
      for (int r = 0; r < bh; ++r) {
        const int y = by * bh + r;
        const double sin_mid = y < height ? std::sin(kPi * (y + 0.5) / height) : 0.0;
        for (int c = 0; c < bw; ++c) {
          const int x = bx * bw + c;
          double w = 0;
          if (x < width && y < height) {
            const float* p = &rgb[(size_t(y) * size_t(width) + size_t(x)) * 3];
            w = luminance(Vec3{p[0], p[1], p[2]}) * sin_mid;
          }
          texel_weights[size_t(r) * size_t(bw) + size_t(c)] = w;
          sum += w;
        }
      }
      mass[size_t(by) * size_t(nbx) + size_t(bx)] = sum;
      append_table(texel_weights, bh, bw, &d.texel_cdfs);
    }

  // Level 1: per normal cell, blocks by mass x the cosine bound.
  std::vector<DVec3> block_dir(mass.size());
  std::vector<double> block_radius(mass.size());
  for (int by = 0; by < nby; ++by)
    for (int bx = 0; bx < nbx; ++bx) {
      const size_t k = size_t(by) * size_t(nbx) + size_t(bx);
      block_radius[k] =
          rectangle_radius(double(bx * bw) / width, double(std::min((bx + 1) * bw, width)) / width,
                           double(by * bh) / height,
                           double(std::min((by + 1) * bh, height)) / height, &block_dir[k]);
    }
  std::vector<double> block_weights(mass.size());
  for (int b = 0; b < normal_bins * normal_bins; ++b) {
    const Vec3 cf = sky_normal_bin_centre(b, normal_bins);
    const DVec3 centre{cf.x, cf.y, cf.z};
    const double spread = normal_cell_radius(b, normal_bins, centre);
    for (size_t k = 0; k < mass.size(); ++k) {
      // No normal of the cell is closer than this to a direction of the
      // block; the cosine of it bounds n.w.
      const double closest = angle_between(centre, block_dir[k]) - spread - block_radius[k];
      block_weights[k] = closest < kHalfPi ? mass[k] * std::cos(std::max(closest, 0.0)) : 0.0;
    }
    append_table(block_weights, nby, nbx, &d.block_cdfs);
  }
  return d;
}

}  // namespace luxel::pipeline
