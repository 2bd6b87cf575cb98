// Procedural HDR environment maps for the encoding benchmark (bench_encode,
// tests/bench/encode.cpp): the stand-ins for the Wells / Uffizi maps of the
// core thesis (Roughton 2019, Figs. 7.5-7.8), generated deterministically in
// code so the benchmark needs no downloads.
//
// Convention: +z is up (the zenith of the sky, and the normal of a lightmap
// texel facing up, i.e. the hemisphere of §7.2.1). Each map is an
// equirectangular RGB float image, W x H texels, texel (x, y) covering azimuth
// phi in [2 pi x / W, 2 pi (x+1) / W) and polar angle theta (from +z) in
// [pi y / H, pi (y+1) / H). A texel holds the AREA AVERAGE of an analytic
// radiance function (stratified supersampling, uniform in solid angle), and
// lookups are NEAREST (piecewise constant). That makes the map itself the
// ground truth: integrals of (map x smooth function) are exact up to the
// sub-texel rule on the smooth factor (EnvQuadrature), so RMSE, moments and
// irradiance references are dense quadratures with no filtering error.
//
// The maps (linear RGB, arbitrary radiance units; luminance is Rec. 709 Y):
//   overcast  CIE standard overcast sky L(theta) = (1 + 2 cos theta) / 3 (zenith
//             1), grey-blue; ground of albedo 0.3 lit by it (L = 0.3 * 7/9).
//             Low dynamic range (about 4:1).
//   sunny     analytic clear sky (blue zenith ~0.3, bright horizon ~0.9, a
//             circumsolar glow) plus a sun disc of angular radius 1 degree and
//             luminance 1e5 (10^5 x the sky) at 40 degrees elevation; sunlit
//             ground of albedo 0.2. The sun disc is larger than the real one
//             (0.27 degrees) so that uniform sampling hits it at all (p = 7.6e-5
//             per sphere sample). Dynamic range > 10^5.
//   clear-sky the sunny map without the sun disc (the sunlit ground and the
//             circumsolar glow stay): what a baker that handles the sun as a
//             separate directional light (next-event estimation) encodes.
//   studio    dark grey background (0.02) with four rectangular area lights:
//             warm key, cool fill, red-magenta strip rim, small white top light.
//             Dynamic range about 3000:1.
//   window    a room interior: dim walls and ceiling, a bright rectangular
//             window on the +x side (sky seen through it, brighter towards the
//             top) and warm floor bounce below with a sunlit patch under the
//             window. Dynamic range about 100:1.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/math.h"

namespace luxel::bench {

struct Rgb {
  float r = 0, g = 0, b = 0;
};

inline float luminance(Rgb c) {
  return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b;
}

enum class EnvMapKind { kOvercast, kSunny, kClearSky, kStudio, kWindow };

class EnvMap {
 public:
  // supersample: s x s stratified analytic evaluations per texel.
  static EnvMap generate(EnvMapKind kind, int width = 512, int height = 256, int supersample = 4);
  static std::vector<EnvMapKind> all_kinds() {
    return {EnvMapKind::kOvercast, EnvMapKind::kSunny, EnvMapKind::kClearSky, EnvMapKind::kStudio,
            EnvMapKind::kWindow};
  }

  EnvMapKind kind() const { return kind_; }
  const char* name() const;
  int width() const { return width_; }
  int height() const { return height_; }

  Rgb texel(int x, int y) const { return texels_[size_t(y) * size_t(width_) + size_t(x)]; }
  // Texel containing the unit direction d (nearest, piecewise constant).
  void texel_of(Vec3 d, int& x, int& y) const;
  Rgb radiance(Vec3 d) const;
  float luminance(Vec3 d) const;
  // The analytic function the texels average (for documentation and checks).
  Rgb analytic(Vec3 d) const;

  // Solid angle of a texel in row y: (2 pi / W) (cos theta_0 - cos theta_1).
  double texel_solid_angle(int y) const;
  // Centre direction of texel (x, y) (mid-phi, mid-cos-theta).
  Vec3 texel_center(int x, int y) const;

  float max_luminance() const { return max_luminance_; }
  float min_luminance() const { return min_luminance_; }
  // Unit direction of the sun (sunny and clear-sky; +z otherwise).
  Vec3 sun_direction() const { return sun_; }

 private:
  EnvMapKind kind_ = EnvMapKind::kOvercast;
  int width_ = 0, height_ = 0;
  std::vector<Rgb> texels_;
  float max_luminance_ = 0, min_luminance_ = 0;
  Vec3 sun_{0, 0, 1};
};

// Dense quadrature matched to the texel grid: each texel (over the whole
// sphere, or only the rows with theta <= pi/2 when upper_only) is split into
// q x q Gauss-Legendre points in (cos theta, phi), with weights that sum to
// the texel's solid angle. value[k] is the map's luminance there (constant
// per texel), so sum_k w_k value_k g(dir_k) integrates map x g for smooth g to
// the accuracy of a q-point rule per texel (about 1e-9 relative for the bases
// here at q = 2 and 512 x 256 texels).
struct EnvQuadrature {
  std::vector<Vec3> directions;
  std::vector<double> weights;
  std::vector<double> values;  // luminance of the map at directions[k]
  double area = 0.0;           // sum of the weights: 4 pi or 2 pi
  static EnvQuadrature build(const EnvMap& map, bool upper_only, int q = 2);
};

// ---- Sampling helpers (all deterministic).

// SplitMix64: small, fast, portable (std::uniform_real_distribution is not
// bit-identical across standard libraries).
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed) {}
  uint64_t next_u64();
  double next_double() { return double(next_u64() >> 11) * 0x1.0p-53; }  // [0, 1)

 private:
  uint64_t state_;
};

// Mixes several integers into one seed (for independent streams per case).
uint64_t mix_seed(uint64_t a, uint64_t b, uint64_t c = 0, uint64_t d = 0);

// Uniform direction on the sphere (z = 1 - 2 u1) or on the hemisphere z >= 0
// (z = u1), phi = 2 pi u2.
Vec3 uniform_direction(double u1, double u2, bool hemisphere);

// Radical inverse of i in the given prime base (van der Corput).
double radical_inverse(uint32_t i, uint32_t base);

// n uniform random directions.
std::vector<Vec3> random_directions(int n, uint64_t seed, bool hemisphere);
// The Halton (2, 3) sequence mapped to directions: a progressive
// low-discrepancy sequence (Fig. 7.6a). offset_u/offset_v apply a
// Cranley-Patterson rotation (0 for the plain sequence) so several
// independent randomised copies can be averaged.
std::vector<Vec3> halton_directions(int n, bool hemisphere, double offset_u = 0.0,
                                    double offset_v = 0.0);
// The Hammersley SET in index order (Fig. 7.6b): u1 = (i + 0.5) / n sweeps
// from pole to pole, so consecutive samples are strongly correlated.
std::vector<Vec3> hammersley_directions(int n, bool hemisphere);

// n spherical Fibonacci points (normals for irradiance tests), on the sphere
// or on the hemisphere z >= 0.
std::vector<Vec3> fibonacci_directions(int n, bool hemisphere);

}  // namespace luxel::bench
