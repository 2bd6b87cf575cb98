// luxel_ad_lut: generates luxel_ad_specular_lut.h, the Ambient Dice specular
// look-up table of the core thesis (Roughton 2019) §8.4.2, Listing 8.2.
//
// For every (n.v, alpha) cell the table holds the ground-truth GGX response
// to one Ambient Dice cosine lobe placed at the GGX dominant direction,
// split into the f0 and f90 Fresnel parts, divided by the value the fit of
// Listing 8.1 (luxel_ad_specular_lobe) gives for that lobe. At run time
// fit * (f0 * lut.x + f90 * lut.y) is then exact for that lobe direction and
// approximate elsewhere (Eq. 8.17).
//
// Ground truth: Monte Carlo over GGX visible normals (Heitz 2018, "Sampling
// the GGX Distribution of Visible Normals"), weight G2 / G1 with the Smith
// height-correlated G2, as Listing 8.2 intends (its printed weight is G2 * G1;
// see g2_over_g1). Samples are a Hammersley set with
// a per-cell Cranley-Patterson rotation from --seed, so output is
// deterministic and independent of cell order.
//
// Built with LUXEL_AD_LUT_NO_MAIN the file is a library of the functions
// below; the tests include it that way to regenerate cells in-process.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "luxel_lightmap.h"
#include "table_print.h"

namespace luxel_sdk {

struct AdLutSettings {
  int size_ndotv = 32;  // texture width: n.v at cell centres (i + 0.5) / size
  int size_alpha = 32;  // texture height: GGX alpha at (j + 0.5) / size
  int samples = 65536;  // Monte Carlo samples per cell
  uint64_t seed = 2019;
};

constexpr double kPi = 3.14159265358979323846;

struct D3 {
  double x, y, z;
};
inline D3 operator+(D3 a, D3 b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
inline D3 operator*(D3 a, double s) {
  return {a.x * s, a.y * s, a.z * s};
}
inline double dot(D3 a, D3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline D3 cross(D3 a, D3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline D3 normalize(D3 a) {
  return a * (1.0 / std::sqrt(dot(a, a)));
}
inline D3 reflect_about(D3 v, D3 h) {
  return h * (2.0 * dot(v, h)) + v * -1.0;
}  // reflect(-v, h)

// Heitz 2018, Listing 1 ("Sampling the GGX Distribution of Visible
// Normals"): a microfacet normal distributed as D_v(h) for view ve.
inline D3 sample_ggx_vndf(D3 ve, double alpha, double u1, double u2) {
  const D3 vh = normalize({alpha * ve.x, alpha * ve.y, ve.z});
  const double lensq = vh.x * vh.x + vh.y * vh.y;
  const D3 t1v = lensq > 0.0 ? D3{-vh.y, vh.x, 0.0} * (1.0 / std::sqrt(lensq)) : D3{1.0, 0.0, 0.0};
  const D3 t2v = cross(vh, t1v);
  const double r = std::sqrt(u1);
  const double phi = 2.0 * kPi * u2;
  const double t1 = r * std::cos(phi);
  double t2 = r * std::sin(phi);
  const double s = 0.5 * (1.0 + vh.z);
  t2 = (1.0 - s) * std::sqrt(1.0 - t1 * t1) + s * t2;
  const D3 nh = t1v * t1 + t2v * t2 + vh * std::sqrt(std::max(0.0, 1.0 - t1 * t1 - t2 * t2));
  return normalize({alpha * nh.x, alpha * nh.y, std::max(0.0, nh.z)});
}

// Smith GGX Lambda (Heitz 2014), tangent space (normal +z), Listing 8.2.
inline double smith_lambda(double cos_theta, double alpha) {
  const double c2 = cos_theta * cos_theta;
  return 0.5 * (-1.0 + std::sqrt(1.0 + alpha * alpha * (1.0 - c2) / c2));
}

// G2 / G1 for the height-correlated Smith G2: the VNDF estimator's weight
// once D and G1(v) cancel against the pdf (Heitz 2018, §2), i.e.
// (1 + Lambda(v)) / (1 + Lambda(v) + Lambda(l)). Listing 8.2 as printed
// returns numerator / (denominator * G1Inverse), which is G2 * G1, not
// G2 / G1; it darkens grazing and rough cells (at alpha 0.5, n.v 0.1 the
// white-furnace albedo came out 0.09 instead of 0.86), so this is the
// corrected weight.
inline double g2_over_g1(D3 v, D3 l, D3 h, double alpha) {
  if (dot(v, h) <= 0.0 || dot(l, h) <= 0.0) return 0.0;
  const double g1_inverse = 1.0 + smith_lambda(v.z, alpha);
  return g1_inverse / (g1_inverse + smith_lambda(l.z, alpha));
}

// Listing 8.2, GGXDominantDirection (called with alpha as "roughness").
inline D3 ggx_dominant_direction(D3 n, D3 r, double roughness) {
  const double smoothness = std::clamp(1.0 - roughness, 0.0, 1.0);
  const double t = smoothness * (std::sqrt(smoothness) + roughness);
  return normalize(n * (1.0 - t) + r * t);
}

inline double radical_inverse2(uint32_t i) {
  i = (i << 16) | (i >> 16);
  i = ((i & 0x55555555u) << 1) | ((i & 0xAAAAAAAAu) >> 1);
  i = ((i & 0x33333333u) << 2) | ((i & 0xCCCCCCCCu) >> 2);
  i = ((i & 0x0F0F0F0Fu) << 4) | ((i & 0xF0F0F0F0u) >> 4);
  i = ((i & 0x00FF00FFu) << 8) | ((i & 0xFF00FF00u) >> 8);
  return double(i) * 0x1p-32;
}

inline uint64_t splitmix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

struct DfgScale {
  double f0 = 0.0, f90 = 0.0;
};

// Listing 8.2, IntegrateDFGAmbientDice: (f0 scale, f90 scale) for one cell.
// The rotation of the Hammersley set derives from (seed, ndotv, alpha) so a
// cell regenerates identically whatever the table size.
inline DfgScale integrate_ad_dfg(double ndotv, double alpha, int samples, uint64_t seed) {
  const D3 n{0.0, 0.0, 1.0};
  const D3 v{0.0, std::sqrt(std::max(0.0, 1.0 - ndotv * ndotv)), ndotv};
  const D3 r = reflect_about(v, n);
  const D3 lobe = ggx_dominant_direction(n, r, alpha);
  const double fitted =
      luxel_ad_specular_lobe(float(dot(n, lobe)), float(dot(r, lobe)), float(alpha));

  uint64_t bits_nv = 0, bits_a = 0;
  std::memcpy(&bits_nv, &ndotv, sizeof ndotv);
  std::memcpy(&bits_a, &alpha, sizeof alpha);
  const uint64_t h = splitmix64(seed ^ splitmix64(bits_nv ^ splitmix64(bits_a)));
  const double shift1 = double(h >> 40) * 0x1p-24, shift2 = double(h & 0xFFFFFFu) * 0x1p-24;

  DfgScale sum;
  for (int k = 0; k < samples; ++k) {
    double u1 = radical_inverse2(uint32_t(k)) + shift1, u2 = (k + 0.5) / samples + shift2;
    u1 -= std::floor(u1);
    u2 -= std::floor(u2);
    const D3 hm = sample_ggx_vndf(v, alpha, u1, u2);
    const D3 l = reflect_about(v, hm);
    if (l.z <= 0.0) continue;
    const double vis = g2_over_g1(v, l, hm, alpha);
    const double w = std::pow(1.0 - std::clamp(dot(v, hm), 0.0, 1.0), 5.0);
    const double basis = luxel_ad_lobe(float(dot(lobe, l)));
    sum.f0 += basis * (1.0 - w) * vis;
    sum.f90 += basis * w * vis;
  }
  return {sum.f0 / samples / fitted, sum.f90 / samples / fitted};
}

// The whole table, row-major by alpha: [2 * (j * size_ndotv + i) + channel].
inline std::vector<float> generate_ad_specular_lut(const AdLutSettings& s) {
  std::vector<float> lut(size_t(2 * s.size_ndotv * s.size_alpha));
  for (int j = 0; j < s.size_alpha; ++j)
    for (int i = 0; i < s.size_ndotv; ++i) {
      const DfgScale d =
          integrate_ad_dfg((i + 0.5) / s.size_ndotv, (j + 0.5) / s.size_alpha, s.samples, s.seed);
      lut[size_t(2 * (j * s.size_ndotv + i))] = float(d.f0);
      lut[size_t(2 * (j * s.size_ndotv + i) + 1)] = float(d.f90);
    }
  return lut;
}

inline std::string ad_lut_header(const std::vector<float>& lut, const AdLutSettings& s) {
  using luxel_tables::appendf;
  std::string out;
  std::string command;
  appendf(
      command,
      "luxel_ad_lut --ndotv %d --alpha %d --samples %d --seed %llu --out luxel_ad_specular_lut.h",
      s.size_ndotv, s.size_alpha, s.samples, static_cast<unsigned long long>(s.seed));
  luxel_tables::append_banner(out,
                              {"luxel_ad_specular_lut.h: GENERATED by luxel_ad_lut "
                               "(server/tools/make_ad_specular_lut.cpp),",
                               "do not edit. Regenerate with:"},
                              command);
  out +=
      " * Ambient Dice specular look-up table (core thesis, Roughton 2019, §8.4.2,\n"
      " * Listing 8.2) for luxel_ad_specular() in luxel_lightmap.h, single-scattering\n"
      " * GGX with Smith height-correlated masking-shadowing.\n"
      " *\n"
      " * Layout: an RG float texture, LUXEL_AD_LUT_SIZE_NDOTV wide and\n"
      " * LUXEL_AD_LUT_SIZE_ALPHA high, row-major: texel (i, j) is\n"
      " *   luxel_ad_specular_lut[2 * (j * LUXEL_AD_LUT_SIZE_NDOTV + i) + c]\n"
      " * at the cell centre n.v = (i + 0.5) / LUXEL_AD_LUT_SIZE_NDOTV (u axis) and\n"
      " * GGX alpha = (j + 0.5) / LUXEL_AD_LUT_SIZE_ALPHA (v axis, alpha = perceptual\n"
      " * roughness squared); c = 0: f0 scale, c = 1: f90 scale. Filter bilinearly\n"
      " * with clamp-to-edge (luxel_ad_lut_sample does exactly that on the CPU).\n"
      " * Each texel = (Monte Carlo ground truth of one cosine lobe at the GGX\n"
      " * dominant direction) / (Listing 8.1 fit for that lobe).\n */\n"
      "#ifndef LUXEL_AD_SPECULAR_LUT_H\n#define LUXEL_AD_SPECULAR_LUT_H\n\n";
  appendf(out,
          "#define LUXEL_AD_LUT_SIZE_NDOTV %d\n#define LUXEL_AD_LUT_SIZE_ALPHA %d\n"
          "#define LUXEL_AD_LUT_SAMPLES %d\n\n",
          s.size_ndotv, s.size_alpha, s.samples);
  out +=
      "#if defined(__OPENCL_VERSION__) || defined(__OPENCL_C_VERSION__)\n__constant\n#else\nstatic "
      "const\n#endif\n"
      "float luxel_ad_specular_lut[2 * LUXEL_AD_LUT_SIZE_NDOTV * LUXEL_AD_LUT_SIZE_ALPHA] = {\n";
  // A row of the texture is 2 * size_ndotv floats (f0, f90 per texel), four
  // texels to a line.
  const size_t row = 2 * size_t(s.size_ndotv);
  for (int j = 0; j < s.size_alpha; ++j) {
    appendf(out, "    /* alpha = %.5f */\n", (j + 0.5) / s.size_alpha);
    luxel_tables::append_float_rows(out, &lut[size_t(j) * row], row, 8, 7, false);
  }
  out += "};\n\n#endif /* LUXEL_AD_SPECULAR_LUT_H */\n";
  return out;
}

}  // namespace luxel_sdk

#ifndef LUXEL_AD_LUT_NO_MAIN
namespace {

int usage(const char* argv0) {
  std::fprintf(
      stderr,
      "usage: %s [--ndotv N] [--alpha N] [--size N] [--samples S] [--seed S] [--out FILE]\n"
      "  --ndotv / --alpha: cells along n.v / GGX alpha (default 32 each; --size sets both)\n"
      "  --samples: Monte Carlo samples per cell (default 65536)\n"
      "  --seed: Cranley-Patterson rotation seed (default 2019)\n"
      "  --out: header to write (default: standard output)\n",
      argv0);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  luxel_sdk::AdLutSettings s;
  const char* out_path = nullptr;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    if (a + 1 >= argc) return usage(argv[0]);
    const char* value = argv[++a];
    char* end = nullptr;
    const long long n = std::strtoll(value, &end, 10);
    const bool numeric = end && *end == '\0' && (n > 0 || (n == 0 && arg == "--seed")) &&
                         n <= (arg == "--seed" ? (1ll << 62) : 1 << 24);
    if (arg == "--out") {
      out_path = value;
    } else if (!numeric) {
      std::fprintf(stderr, "%s: '%s' is not a positive integer in range\n", arg.c_str(), value);
      return usage(argv[0]);
    } else if (arg == "--ndotv") {
      s.size_ndotv = int(n);
    } else if (arg == "--alpha") {
      s.size_alpha = int(n);
    } else if (arg == "--size") {
      s.size_ndotv = s.size_alpha = int(n);
    } else if (arg == "--samples") {
      s.samples = int(n);
    } else if (arg == "--seed") {
      s.seed = uint64_t(n);
    } else {
      std::fprintf(stderr, "unknown option %s\n", arg.c_str());
      return usage(argv[0]);
    }
  }
  const std::string text = luxel_sdk::ad_lut_header(luxel_sdk::generate_ad_specular_lut(s), s);
  if (!luxel_tables::write_table(text, out_path)) return 1;
  if (out_path)
    std::fprintf(stderr, "wrote %s (%d x %d cells, %d samples each)\n", out_path, s.size_ndotv,
                 s.size_alpha, s.samples);
  return 0;
}
#endif
