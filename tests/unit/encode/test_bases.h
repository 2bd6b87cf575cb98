// Minimal synthetic bases, signals and sample sets for the solver tests.
// Deliberately independent of the engine's basis code (server/engine/encode).
#pragma once

#include <cmath>
#include <numbers>
#include <random>
#include <span>
#include <vector>

#include "encode/solvers.h"

namespace luxel::encode::testing {

struct Vec3 {
  double x, y, z;
};

// n points of a Fibonacci spiral on the sphere (z >= 0 only when hemisphere).
inline std::vector<Vec3> fibonacci_directions(int n, bool hemisphere = false) {
  std::vector<Vec3> dirs;
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = hemisphere ? 1.0 - (i + 0.5) / n : 1.0 - 2.0 * (i + 0.5) / n;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    dirs.push_back({r * std::cos(golden * i), r * std::sin(golden * i), z});
  }
  return dirs;
}

inline Vec3 uniform_direction(double u1, double u2, bool hemisphere) {
  const double z = hemisphere ? u1 : 1.0 - 2.0 * u1;
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  const double phi = 2.0 * std::numbers::pi * u2;
  return {r * std::cos(phi), r * std::sin(phi), z};
}

inline std::vector<Vec3> random_directions(int n, uint64_t seed, bool hemisphere = false) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3> dirs;
  for (int i = 0; i < n; ++i) {
    const double u1 = u(rng), u2 = u(rng);
    dirs.push_back(uniform_direction(u1, u2, hemisphere));
  }
  return dirs;
}

// The Hammersley set in index order: u1 = i/n sweeps the sphere from pole to
// pole, so early samples all lie in one region (the correlated case, Fig. 7.6).
inline std::vector<Vec3> hammersley_directions(int n, bool hemisphere = false) {
  std::vector<Vec3> dirs;
  for (uint32_t i = 0; i < uint32_t(n); ++i) {
    uint32_t bits = i;
    bits = (bits << 16u) | (bits >> 16u);
    bits = ((bits & 0x55555555u) << 1u) | ((bits & 0xAAAAAAAAu) >> 1u);
    bits = ((bits & 0x33333333u) << 2u) | ((bits & 0xCCCCCCCCu) >> 2u);
    bits = ((bits & 0x0F0F0F0Fu) << 4u) | ((bits & 0xF0F0F0F0u) >> 4u);
    bits = ((bits & 0x00FF00FFu) << 8u) | ((bits & 0xFF00FF00u) >> 8u);
    dirs.push_back(uniform_direction((i + 0.5) / n, bits * 2.3283064365386963e-10, hemisphere));
  }
  return dirs;
}

// Spherical Gaussians B_i(w) = exp(lambda (mu_i . w - 1)), axes on a
// Fibonacci spiral over the domain.
inline Basis sg_basis(int lobes, double lambda, Domain domain = Domain::kSphere) {
  const std::vector<Vec3> axes = fibonacci_directions(lobes, domain == Domain::kHemisphere);
  Basis basis;
  basis.count = lobes;
  basis.domain = domain;
  basis.evaluate = [axes, lambda](const double d[3], double* values) {
    for (size_t i = 0; i < axes.size(); ++i) {
      values[i] = std::exp(lambda * (axes[i].x * d[0] + axes[i].y * d[1] + axes[i].z * d[2] - 1.0));
    }
  };
  return basis;
}

// Real orthonormal SH up to L2 (9 functions).
inline Basis sh2_basis(bool with_identity_gram) {
  Basis basis;
  basis.count = 9;
  basis.evaluate = [](const double d[3], double* v) {
    const double x = d[0], y = d[1], z = d[2];
    v[0] = 0.282094791773878;
    v[1] = 0.488602511902920 * y;
    v[2] = 0.488602511902920 * z;
    v[3] = 0.488602511902920 * x;
    v[4] = 1.092548430592079 * x * y;
    v[5] = 1.092548430592079 * y * z;
    v[6] = 0.315391565252520 * (3.0 * z * z - 1.0);
    v[7] = 1.092548430592079 * x * z;
    v[8] = 0.546274215296040 * (x * x - y * y);
  };
  if (with_identity_gram) {
    std::vector<double> g(81, 0.0);
    for (int i = 0; i < 9; ++i) g[i * 9 + i] = 1.0;
    basis.gram = g;
  }
  return basis;
}

// A smooth test signal: a non-negative combination of the basis plus a sharp
// lobe the basis cannot represent (weight `extra`).
struct Signal {
  const Basis* basis;
  std::vector<double> weights;
  Vec3 sharp_axis{0.3, -0.5, 0.812404};
  double extra = 1.0;

  double operator()(const Vec3& d) const {
    const double dir[3] = {d.x, d.y, d.z};
    const double cos_sharp =
        std::max(0.0, sharp_axis.x * d.x + sharp_axis.y * d.y + sharp_axis.z * d.z);
    return reconstruct(*basis, weights, dir) + extra * std::pow(cos_sharp, 16.0);
  }
};

inline std::vector<double> random_non_negative_weights(int n, uint64_t seed, double zero_fraction) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> w(n);
  for (double& v : w) v = u(rng) < zero_fraction ? 0.0 : 0.2 + u(rng);
  return w;
}

template <typename F>
std::vector<Sample> sample_signal(const std::vector<Vec3>& dirs, const F& f) {
  std::vector<Sample> samples;
  for (const Vec3& d : dirs) samples.push_back({{d.x, d.y, d.z}, f(d)});
  return samples;
}

// RMS over dense quasi-uniform points of the domain of (a - b), where a, b are
// callables of a direction: the function-space error of Eq. 7.2.
template <typename A, typename B>
double function_rms_difference(const A& a, const B& b, bool hemisphere = false, int points = 4096) {
  double sum = 0.0;
  for (const Vec3& d : fibonacci_directions(points, hemisphere)) {
    const double e = a(d) - b(d);
    sum += e * e;
  }
  return std::sqrt(sum / points);
}

inline auto reconstruction(const Basis& basis, const std::vector<double>& coefficients) {
  return [&basis, &coefficients](const Vec3& d) {
    const double dir[3] = {d.x, d.y, d.z};
    return reconstruct(basis, coefficients, dir);
  };
}

}  // namespace luxel::encode::testing
