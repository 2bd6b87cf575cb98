// Spherical bases for directional lightmaps (core thesis, Roughton 2019,
// Ch. 8): what a basis is (kind, lobe directions, sharpness, domain), how to
// evaluate it, and how to reconstruct diffuse irradiance from its radiance
// coefficients. Per-direction maths is shared with kernels through
// kernels/shared/bases.h so host and device agree bit for bit in float.
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "common/math.h"
#include "common/status.h"

namespace luxel::encode {

// Every directional encoding by name, declared once: SphericalBasis::from_name
// parses these, and the settings schema offers them (with "irradiance") as
// settings.encodings' choices, in this order.
inline constexpr std::array<std::string_view, 10> kEncodingNames = {
    "sh1",      "sh2",      "sg6",       "sg9",           "sg12",
    "sg6-hemi", "sg9-hemi", "sg12-hemi", "ambient-dice9", "ambient-dice12"};

enum class BasisKind {
  kShL1,               // 4 real SH coefficients (§8.1)
  kShL2,               // 9 real SH coefficients
  kSphericalGaussian,  // N lobes of Eq. 8.2, fixed directions and sharpness
  kAmbientDice,        // cosine lobes of Eq. 8.3/8.4 (12 sphere, 9 hemisphere)
};

// Where lobes are placed (SG) or where the least-squares error is minimised
// (§7.2.1). The hemisphere is z >= 0 in tangent space (normal = +z).
enum class BasisDomain { kSphere, kHemisphere };

struct BasisSpec {
  BasisKind kind = BasisKind::kShL2;
  // SG: 6, 9 or 12. Ambient Dice: 12 (icosahedron) or 9 (hemisphere set of
  // §8.3.1). Ignored for SH.
  int lobe_count = 0;
  // SG sharpness lambda of Eq. 8.2; §8.3.2 suggests ~3.4. Ignored otherwise.
  float sharpness = 3.4f;
  // SG only: directions on the whole sphere or on the hemisphere z >= 0.
  BasisDomain lobe_layout = BasisDomain::kSphere;
  // Least-squares domain (§7.2.1); recorded for the solver and the manifest.
  BasisDomain fit_domain = BasisDomain::kSphere;
};

// Everything an engine needs to reconstruct from the coefficients.
struct BasisDescription {
  std::string name;           // "sh1", "sh2", "sg12", "ambient-dice9", ...
  std::string function;       // the formula of B_i in words
  std::string normalisation;  // how coefficients relate to radiance
  std::string layout;         // how directions were generated
  std::string fit_domain;     // "sphere" or "hemisphere (z >= 0)"
  float sharpness = 0.0f;     // SG lambda, 0 otherwise
  std::vector<Vec3> directions;
  std::string to_json() const;  // one JSON object for the bake manifest
};

class SphericalBasis {
 public:
  static Result<SphericalBasis> create(const BasisSpec& spec);
  // "sh1", "sh2", "sg6|sg9|sg12" (optional "-hemi"), "ambient-dice9|12".
  static Result<SphericalBasis> from_name(std::string_view name, float sg_sharpness = 3.4f);

  int size() const { return count_; }
  const BasisSpec& spec() const { return spec_; }
  // Lobe axes (SG) or vertices (Ambient Dice); empty for SH.
  const std::vector<Vec3>& directions() const { return directions_; }

  // out[0 .. size()-1] = B_i(w) for a unit direction w.
  void evaluate(Vec3 w, float* out) const;
  std::vector<float> evaluate(Vec3 w) const;

  // Irradiance at unit normal n from radiance coefficients (size() of them):
  // SH by cosine convolution (exact), SG by Hill's fit, Ambient Dice by the
  // quadratic fit of Eq. 8.14 / 8.15. Constant radiance L gives ~pi * L.
  float diffuse_irradiance(const float* coefficients, Vec3 n) const;

  BasisDescription describe() const;

 private:
  BasisSpec spec_;
  int count_ = 0;
  std::vector<Vec3> directions_;
};

// Deterministic lobe layouts, exposed for tests and tools.
// Spherical Fibonacci ("Vogel's sphere", §8.3.2): z_i = 1 - (2i + 1) / N,
// phi_i = i * golden angle; hemisphere variant z_i = 1 - (i + 0.5) / N.
std::vector<Vec3> spherical_fibonacci(int count, BasisDomain domain);
// The 12 vertices of the regular icosahedron (0, +-1, +-phi) and cyclic
// permutations, normalised.
std::vector<Vec3> icosahedron_vertices();
// The nine vertices of §8.3.1 (published to 4 digits), renormalised.
std::vector<Vec3> ambient_dice_hemisphere_vertices();

}  // namespace luxel::encode
