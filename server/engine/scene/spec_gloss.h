// KHR_materials_pbrSpecularGlossiness -> the core metallic-roughness model.
//
// The bake has one material model (glTF 2.0 Appendix B), so the importer
// converts specular-glossiness materials once, with the conversion the
// extension's own repository documents (KhronosGroup/glTF,
// extensions/2.0/Archived/KHR_materials_pbrSpecularGlossiness, README
// "Appendix: Conversion between the two PBR material models", the sample
// examples/convert-between-workflows/js/three.pbrUtilities.js,
// ConvertToMetallicRoughness). glTF-Transform's metalRough() converts
// differently (KHR_materials_specular and KHR_materials_ior carry the
// specular colour); the Khronos solve is used here because it keeps the
// core model's metallic mix, which the bake's BRDF layers are built for:
//
//   roughness = 1 - glossiness
//   s = 1 - max(specular.rgb)                      (one minus specular strength)
//   metallic = 0 when B(specular) < 0.04, else the root in [0, 1] of
//     0.04 m^2 + (B(diffuse) s / 0.96 + B(specular) - 0.08) m + (0.04 - B(specular)) = 0
//   base = mix(diffuse s / 0.96 / max(1 - m, 1e-6),
//              (specular - 0.04 (1 - m)) / max(m, 1e-6), m^2), clamped to [0, 1]
//   alpha = diffuse alpha
//
// B(c) = sqrt(0.299 r^2 + 0.587 g^2 + 0.114 b^2) is the "perceived
// brightness" of linear RGB and 0.04 the dielectric F0 of Appendix B (ior
// 1.5). A pure dielectric (specular 0.04) gives metallic 0 and base =
// diffuse; a pure metal (diffuse black) gives metallic 1 and base = specular.
// The conversion is not linear, so textures are converted per texel
// (convert_spec_gloss_textures), not by converting the factors alone.
#pragma once

#include "common/math.h"
#include "scene/scene.h"

namespace luxel::scene::detail {

struct SpecGloss {
  Vec4 diffuse{1, 1, 1, 1};  // linear rgb, a = alpha coverage
  Vec3 specular{1, 1, 1};    // linear F0
  float glossiness = 1.0f;
};

struct MetalRough {
  Vec4 base_color{1, 1, 1, 1};  // linear rgb, a = alpha coverage
  float metallic = 0.0f;
  float roughness = 0.0f;
};

// The conversion above for one set of values (computed in double).
MetalRough spec_gloss_to_metal_rough(const SpecGloss& in);

// The extension's inputs: factors times textures (either texture may be
// absent: nullptr). Textures must have pixels (Texture::has_pixels), their
// rgb already linear (diffuse and specular are sRGB in the file; glossiness,
// the specular texture's alpha, is linear).
struct SpecGlossInputs {
  SpecGloss factors;
  const Texture* diffuse = nullptr;
  const Texture* specular_glossiness = nullptr;
};

// The converted textures: base colour (linear rgb, alpha) and metallic-
// roughness (G = roughness, B = metallic, as glTF 2.0 §3.9.2 packs them), both
// RGBA16F (already linear) at the larger of the two inputs' sizes, the
// factors folded in (the material's factors become 1). When the inputs
// differ in size each output texel reads the input texel whose centre is
// nearest its own centre (same UV mapping, checked by the caller).
struct ConvertedTextures {
  Texture base_color;
  Texture metallic_roughness;
};
ConvertedTextures convert_spec_gloss_textures(const SpecGlossInputs& in);

}  // namespace luxel::scene::detail
