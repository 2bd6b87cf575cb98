// See spec_gloss.h.
#include "scene/spec_gloss.h"

#include <algorithm>
#include <cmath>

#include "common/half.h"

namespace luxel::scene::detail {
namespace {

// Appendix B's dielectric F0 (ior 1.5), which the conversion assumes.
constexpr double kDielectricF0 = 0.04;
constexpr double kEpsilon = 1e-6;

double brightness(double r, double g, double b) {
  return std::sqrt(0.299 * r * r + 0.587 * g * g + 0.114 * b * b);
}

double clamp01(double x) {
  return std::min(std::max(x, 0.0), 1.0);
}

// Input texel (x, y) of an output grid w x h: the texel of `t` whose centre
// is nearest the output texel's centre.
Vec4 sample_nearest(const Texture& t, int x, int y, int w, int h) {
  const int tx = std::min(t.width - 1, static_cast<int>((x + 0.5) * t.width / w));
  const int ty = std::min(t.height - 1, static_cast<int>((y + 0.5) * t.height / h));
  return t.linear(static_cast<size_t>(ty) * static_cast<size_t>(t.width) + static_cast<size_t>(tx));
}

}  // namespace

MetalRough spec_gloss_to_metal_rough(const SpecGloss& in) {
  const double d[3] = {in.diffuse.x, in.diffuse.y, in.diffuse.z};
  const double s[3] = {in.specular.x, in.specular.y, in.specular.z};
  const double one_minus_strength = 1.0 - std::max({s[0], s[1], s[2]});
  const double bd = brightness(d[0], d[1], d[2]), bs = brightness(s[0], s[1], s[2]);
  // The quadratic of ConvertToMetallicRoughness's solveMetallic: the
  // metallic that reproduces the specular's brightness as mix(0.04, base, m)
  // with the diffuse's brightness as base (1 - m) scaled back by 1 - 0.04.
  double metallic = 0.0;
  if (bs >= kDielectricF0) {
    const double a = kDielectricF0;
    const double b = bd * one_minus_strength / (1.0 - kDielectricF0) + bs - 2.0 * kDielectricF0;
    const double c = kDielectricF0 - bs;
    const double disc = std::max(b * b - 4.0 * a * c, 0.0);
    metallic = clamp01((-b + std::sqrt(disc)) / (2.0 * a));
  }
  MetalRough out;
  float base[3];
  for (int i = 0; i < 3; ++i) {
    const double from_diffuse =
        d[i] * one_minus_strength / (1.0 - kDielectricF0) / std::max(1.0 - metallic, kEpsilon);
    const double from_specular =
        (s[i] - kDielectricF0 * (1.0 - metallic)) / std::max(metallic, kEpsilon);
    const double t = metallic * metallic;
    base[i] = static_cast<float>(clamp01(from_diffuse + (from_specular - from_diffuse) * t));
  }
  out.base_color = {base[0], base[1], base[2], in.diffuse.w};
  out.metallic = static_cast<float>(metallic);
  out.roughness = static_cast<float>(clamp01(1.0 - double(in.glossiness)));
  return out;
}

ConvertedTextures convert_spec_gloss_textures(const SpecGlossInputs& in) {
  const Texture* d = in.diffuse;
  const Texture* sg = in.specular_glossiness;
  const int w = std::max(d ? d->width : 0, sg ? sg->width : 0);
  const int h = std::max(d ? d->height : 0, sg ? sg->height : 0);
  ConvertedTextures out;
  for (Texture* t : {&out.base_color, &out.metallic_roughness}) {
    t->width = w;
    t->height = h;
    t->format = TexelFormat::kRGBA16F;
    t->source_space = ColorSpace::kLinear;
    t->rgba16f.resize(t->texel_count() * 4);
  }
  const SpecGloss& f = in.factors;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      SpecGloss v = f;
      if (d) {
        const Vec4 t = sample_nearest(*d, x, y, w, h);
        v.diffuse = {f.diffuse.x * t.x, f.diffuse.y * t.y, f.diffuse.z * t.z, f.diffuse.w * t.w};
      }
      if (sg) {
        const Vec4 t = sample_nearest(*sg, x, y, w, h);
        v.specular = {f.specular.x * t.x, f.specular.y * t.y, f.specular.z * t.z};
        v.glossiness = f.glossiness * t.w;
      }
      const MetalRough mr = spec_gloss_to_metal_rough(v);
      const size_t i =
          (static_cast<size_t>(y) * static_cast<size_t>(w) + static_cast<size_t>(x)) * 4;
      const float base[4] = {mr.base_color.x, mr.base_color.y, mr.base_color.z, mr.base_color.w};
      const float packed[4] = {0.0f, mr.roughness, mr.metallic, 1.0f};
      for (int c = 0; c < 4; ++c) {
        out.base_color.rgba16f[i + static_cast<size_t>(c)] = float_to_half(base[c]);
        out.metallic_roughness.rgba16f[i + static_cast<size_t>(c)] = float_to_half(packed[c]);
      }
    }
  }
  return out;
}

}  // namespace luxel::scene::detail
