// Ground truth for the specular tests: integral over the hemisphere (n = +z,
// tangent space) of L(l) f(v, l) (n.l) dl for single-scattering GGX with the
// Smith height-correlated G2 and Fresnel f0 + (f90 - f0)(1 - v.h)^5.
// Deliberately NOT the generator's estimator: half vectors are drawn from
// D(h)(n.h) (Walter et al. 2007), not from the visible normals of Heitz 2018,
// so the LUT's sampling code is checked too. Hammersley points, double.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace luxel_test {

struct D3 {
  double x, y, z;
};
inline double dot(D3 a, D3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}

inline double hammersley_radical(uint32_t i) {
  i = (i << 16) | (i >> 16);
  i = ((i & 0x55555555u) << 1) | ((i & 0xAAAAAAAAu) >> 1);
  i = ((i & 0x33333333u) << 2) | ((i & 0xCCCCCCCCu) >> 2);
  i = ((i & 0x0F0F0F0Fu) << 4) | ((i & 0xF0F0F0F0u) >> 4);
  i = ((i & 0x00FF00FFu) << 8) | ((i & 0xFF00FF00u) >> 8);
  return double(i) * 0x1p-32;
}

inline double ggx_lambda(double cos_theta, double alpha) {
  const double c2 = cos_theta * cos_theta;
  return 0.5 * (-1.0 + std::sqrt(1.0 + alpha * alpha * (1.0 - c2) / c2));
}

// The integral split by Fresnel channel: result = f0 * .f0 + f90 * .f90.
struct FresnelSplit {
  double f0 = 0.0, f90 = 0.0;
};

// View v (unit, v.z > 0), GGX alpha, radiance(l) for unit l.
template <class Radiance>
FresnelSplit ggx_specular_truth_split(const Radiance& radiance, D3 v, double alpha, int samples) {
  const double pi = 3.14159265358979323846;
  FresnelSplit sum;
  for (int k = 0; k < samples; ++k) {
    const double u1 = (k + 0.5) / samples, u2 = hammersley_radical(uint32_t(k));
    const double tan2 = alpha * alpha * u1 / (1.0 - u1);
    const double ch = 1.0 / std::sqrt(1.0 + tan2), sh = std::sqrt(std::max(0.0, 1.0 - ch * ch));
    const D3 h{sh * std::cos(2.0 * pi * u2), sh * std::sin(2.0 * pi * u2), ch};
    const double vh = dot(v, h);
    if (vh <= 0.0) continue;
    const D3 l{2.0 * vh * h.x - v.x, 2.0 * vh * h.y - v.y, 2.0 * vh * h.z - v.z};
    if (l.z <= 0.0) continue;
    const double g2 = 1.0 / (1.0 + ggx_lambda(v.z, alpha) + ggx_lambda(l.z, alpha));
    const double w = std::pow(1.0 - vh, 5.0);
    // f cos / pdf(l) with pdf(l) = D(h) (n.h) / (4 v.h): D cancels.
    const double common = radiance(l) * g2 * vh / (v.z * h.z);
    sum.f0 += common * (1.0 - w);
    sum.f90 += common * w;
  }
  sum.f0 /= samples;
  sum.f90 /= samples;
  return sum;
}

template <class Radiance>
double ggx_specular_truth(const Radiance& radiance, D3 v, double alpha, double f0, double f90,
                          int samples) {
  const FresnelSplit s = ggx_specular_truth_split(radiance, v, alpha, samples);
  return f0 * s.f0 + f90 * s.f90;
}

}  // namespace luxel_test
