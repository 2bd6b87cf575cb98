// Directional encodings of a bake (core thesis Ch. 7-8): which bases
// the bake accumulates besides irradiance, how each is solved, and the
// device tables that describe them to kernels/bake/basis.h.
//
// Conventions (recorded in every manifest, see describe_json):
//  - Coefficients encode incident RADIANCE L(w) at the texel; reconstructed
//    irradiance is E(n) = integral over the hemisphere of L (n.w), the same
//    quantity as irradiance.exr.
//  - Frame: sphere-domain bases (SH, SG on the sphere, Ambient Dice 12) use
//    world-space directions; hemisphere bases (SG "-hemi", Ambient Dice 9 of
//    §8.3.1) use the texel's tangent frame: z = shading normal, x = the
//    surface direction of increasing lightmap u (TEXCOORD_1), y = z x x.
//  - Fit domain: the hemisphere for hemisphere bases (§7.2.1); the sphere
//    (radiance 0 below the surface) otherwise.
#pragma once

#include <string>
#include <vector>

#include "common/choices.h"
#include "common/status.h"
#include "encode/basis.h"
#include "kernels/shared/bake.h"

namespace luxel::pipeline {

// The settings' solver choice (common/choices.h).
#define LUXEL_SOLVER_CHOICES(X)                                                                   \
  X(kAuto, "auto")               /* SH: projection; SG, Ambient Dice: progressive non-negative */ \
  X(kProjection, "projection")   /* naive projection (Monte Carlo moments) */                     \
  X(kProgressive, "progressive") /* Listing 7.1, Gauss-Seidel */                                  \
  X(kProgressiveNonNegative, "progressive-nn") /* Listing 7.1, amplitudes >= 0 (§7.3.1) */
LUXEL_CHOICE_ENUM(EncodingSolver, LUXEL_SOLVER_CHOICES)

struct EncodingSettings {
  // Directional encodings besides irradiance (always baked): "sh1", "sh2",
  // "sg6" / "sg9" / "sg12" (optional "-hemi"), "ambient-dice9" / "ambient-dice12".
  std::vector<std::string> names;
  float sg_sharpness = 3.4f;  // SG lambda (Eq. 8.2; §8.3.2 suggests ~3.4)
  EncodingSolver solver = EncodingSolver::kAuto;
  float acceleration = 3.0f;  // alpha of Eq. 7.14 (§7.3: 3 converges quickest)
};

// Splits "irradiance,sh2,sg12" into the directional names (irradiance is
// implicit and dropped); INVALID_ARGUMENT names an unknown entry.
Result<std::vector<std::string>> parse_encoding_list(const std::string& list);

// INVALID_ARGUMENT naming settings.encodings / sg_sharpness / acceleration.
Status validate_encodings(const EncodingSettings& e);

// One resolved encoding.
struct Encoding {
  encode::SphericalBasis basis;
  EncodingSolver solver;  // never kAuto
  bool tangent_frame;
  std::string name() const { return basis.describe().name; }
  // The manifest entry: basis description plus frame, solver and file.
  // residual_rms < 0: not recorded (projection solver).
  std::string describe_json(const std::string& file, float acceleration, double residual_rms) const;
};

struct EncodingPlan {
  std::vector<Encoding> encodings;
  std::vector<cl::LuxEncoding> table;  // device table, one per encoding
  std::vector<cl::float4> directions;  // lobe directions of SG and Ambient Dice
  uint32_t stride = 0;                 // float4 of state per texel
  bool empty() const { return encodings.empty(); }
  size_t bytes_per_texel() const { return size_t{stride} * 16; }
};

Result<EncodingPlan> plan_encodings(const EncodingSettings& settings);

// Coefficients of encoding k from the device state of n covered slots
// (stride float4 each), written at texels[slot] into `out`: texel-major,
// count * 3 floats (lobe-major RGB), sized by the caller (uncovered texels
// keep what they hold, 0).
void extract_coefficients(const EncodingPlan& plan, size_t k, const std::vector<cl::float4>& state,
                          const uint32_t* texels, size_t n, std::vector<float>& out);

}  // namespace luxel::pipeline
