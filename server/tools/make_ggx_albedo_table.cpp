// luxel_ggx_albedo: generates kernels/shading/ggx_albedo_table.h, the
// directional albedo E(mu, roughness) and its cosine-weighted average
// E_avg(roughness) of the single-scattering GGX lobe with F = 1, which the
// Kulla-Conty multiple-scattering compensation of kernels/shading/bsdf.h
// needs (Kulla & Conty 2017, "Revisiting Physically Based Shading at
// Imageworks", SIGGRAPH course slides, "Energy compensation": E(mu) and
// E_avg = 2 int_0^1 E(mu) mu dmu).
//
// The lobe is the one bsdf.h evaluates: GGX D, Smith height-correlated G2
// (Heitz 2014, "Understanding the Masking-Shadowing Function in
// Microfacet-Based BRDFs", Eq. 99), alpha = max(roughness^2, 1e-3)
// (LUX_BSDF_MIN_ALPHA). E(mu) is estimated by sampling visible normals
// (Heitz 2018, "Sampling the GGX Distribution of Visible Normals") with the
// weight G2 / G1(wo), over a Hammersley set with a fixed Cranley-Patterson
// rotation per cell: deterministic and independent of cell order.
//
// Grid: LUX_GGX_ALBEDO_SIZE nodes on each axis, at sqrt(mu) = i / (size - 1)
// (node 0 evaluated at mu = 1e-4, the kernel's floor for wo.z; the square
// root crowds nodes towards grazing, where E falls fastest) and roughness =
// j / (size - 1); the kernel interpolates bilinearly in (sqrt(mu),
// roughness). E_avg is not sampled separately: it is the exact integral
// 2 int E(mu) mu dmu of each row's interpolant, so the compensation lobe built
// from the table reflects exactly 1 - E_table(mu_o) (energy conservation
// does not depend on the Monte Carlo error of E_avg).
//
// Built with LUXEL_GGX_ALBEDO_NO_MAIN the file is a library of the functions
// below; tests/unit/kernels/ggx_albedo_table_test.cpp includes it that way to
// regenerate the table in-process.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "common/dvec3.h"
#include "table_print.h"

namespace luxel_ggx_albedo {

struct Settings {
  int size = 32;        // nodes along mu and along roughness
  int samples = 16384;  // Hammersley points per node
};

constexpr double kPi = 3.14159265358979323846;
constexpr double kMinAlpha = 1e-3;  // LUX_BSDF_MIN_ALPHA
constexpr double kMinMu = 1e-4;     // shade.h clamps wo.z to at least this

using luxel::cross;
using luxel::dot;
using luxel::DVec3;
using luxel::normalize;

inline double alpha_of(double roughness) {
  return std::max(roughness * roughness, kMinAlpha);
}

// Smith Lambda for GGX (Heitz 2014, Eq. 72), z = cos theta of w.
inline double lambda(DVec3 w, double alpha) {
  const double t2 = (w.x * w.x + w.y * w.y) / (w.z * w.z);
  return 0.5 * (std::sqrt(1.0 + alpha * alpha * t2) - 1.0);
}

// Heitz 2018, Listing 1.
inline DVec3 sample_vndf(DVec3 v, double alpha, double u1, double u2) {
  const DVec3 vh = normalize({alpha * v.x, alpha * v.y, v.z});
  const double len2 = vh.x * vh.x + vh.y * vh.y;
  const DVec3 t1 =
      len2 > 0.0 ? DVec3{-vh.y, vh.x, 0.0} * (1.0 / std::sqrt(len2)) : DVec3{1.0, 0.0, 0.0};
  const DVec3 t2 = cross(vh, t1);
  const double r = std::sqrt(u1), phi = 2.0 * kPi * u2;
  const double p1 = r * std::cos(phi);
  const double s = 0.5 * (1.0 + vh.z);
  const double p2 = (1.0 - s) * std::sqrt(std::max(0.0, 1.0 - p1 * p1)) + s * r * std::sin(phi);
  const DVec3 nh = t1 * p1 + t2 * p2 + vh * std::sqrt(std::max(0.0, 1.0 - p1 * p1 - p2 * p2));
  return normalize({alpha * nh.x, alpha * nh.y, std::max(0.0, nh.z)});
}

inline double radical_inverse2(uint32_t i) {
  i = (i << 16) | (i >> 16);
  i = ((i & 0x55555555u) << 1) | ((i & 0xAAAAAAAAu) >> 1);
  i = ((i & 0x33333333u) << 2) | ((i & 0xCCCCCCCCu) >> 2);
  i = ((i & 0x0F0F0F0Fu) << 4) | ((i & 0xF0F0F0F0u) >> 4);
  i = ((i & 0x00FF00FFu) << 8) | ((i & 0xFF00FF00u) >> 8);
  return double(i) * 0x1p-32;
}

// E(mu) for F = 1: the mean of G2 / G1(wo) over visible normals whose
// reflection lies above the horizon (D and the reflection Jacobian cancel
// against the visible-normal density).
inline double directional_albedo(double mu, double roughness, int samples) {
  mu = std::clamp(mu, kMinMu, 1.0);
  const double alpha = alpha_of(roughness);
  const DVec3 v{std::sqrt(std::max(0.0, 1.0 - mu * mu)), 0.0, mu};
  const double lv = lambda(v, alpha);
  double sum = 0.0;
  for (int k = 0; k < samples; ++k) {
    // A fixed irrational rotation keeps the points off the grid lines.
    double u1 = radical_inverse2(uint32_t(k)) + 0.3819660112501051;
    double u2 = (k + 0.5) / samples + 0.6180339887498949;
    u1 -= std::floor(u1);
    u2 -= std::floor(u2);
    const DVec3 h = sample_vndf(v, alpha, u1, u2);
    const DVec3 l = h * (2.0 * dot(v, h)) + v * -1.0;
    if (l.z <= 0.0) continue;
    sum += (1.0 + lv) / (1.0 + lv + lambda(l, alpha));
  }
  return sum / samples;
}

struct Table {
  int size = 0;
  std::vector<float> e;      // [j * size + i]: roughness j / (size-1), mu i / (size-1)
  std::vector<float> e_avg;  // [j]
  // [j * (size - 1) + i]: the distribution bsdf.h samples the compensation
  // lobe from, cumulative over the cells [i, i + 1] / (size - 1) of sqrt(mu)
  // (last entry 1).
  std::vector<float> ms_cdf;
};

// 2 int_0^1 E(mu) mu dmu of the interpolant through the row's nodes,
// exactly: E is linear in x = sqrt(mu) on each interval, mu dmu = 2 x^3 dx,
// so the integrand 4 E(x) x^3 is a quartic in x and 3-point Gauss-Legendre
// is exact on each interval.
inline double row_average(const float* row, int size) {
  const double h = 1.0 / (size - 1);
  const double nodes[3] = {-std::sqrt(0.6), 0.0, std::sqrt(0.6)};
  const double weights[3] = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
  double sum = 0.0;
  for (int i = 0; i + 1 < size; ++i)
    for (int q = 0; q < 3; ++q) {
      const double t = 0.5 * (1.0 + nodes[q]), x = (i + t) * h;
      const double e = row[i] + (double(row[i + 1]) - row[i]) * t;
      sum += weights[q] * 0.5 * h * 4.0 * e * x * x * x;
    }
  return sum;
}

// The compensation lobe's cosine-weighted shape (1 - E(mu)) mu per cell of
// sqrt(mu), int (1 - E) mu dmu = int (1 - E(x)) 2 x^3 dx (quartic, exact by
// 3-point Gauss-Legendre), normalized and accumulated. bsdf.h samples a cell
// from it and mu within the cell proportionally to mu, so its density is
// piecewise c_i mu with c_i the cell's mean of 1 - E: the weight f / pdf
// stays near (1 - E(mu)) / c_i ~ 1 instead of (1 - E(mu)) / (1 - E_avg)
// under plain cosine sampling. A floor of 1e-9 of cosine weight per cell
// keeps every cell sampleable.
inline std::vector<double> ms_cdf_row(const float* row, int size) {
  const double h = 1.0 / (size - 1);
  const double nodes[3] = {-std::sqrt(0.6), 0.0, std::sqrt(0.6)};
  const double weights[3] = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
  std::vector<double> cdf(size_t(size - 1));
  double sum = 0.0;
  for (int i = 0; i + 1 < size; ++i) {
    double w = 0.0;
    for (int q = 0; q < 3; ++q) {
      const double t = 0.5 * (1.0 + nodes[q]), x = (i + t) * h;
      const double e = row[i] + (double(row[i + 1]) - row[i]) * t;
      w += weights[q] * 0.5 * h * std::max(0.0, 1.0 - e) * 2.0 * x * x * x;
    }
    const double xa = i * h, xb = (i + 1) * h;
    sum += w + 1e-9 * (std::pow(xb, 4.0) - std::pow(xa, 4.0));
    cdf[size_t(i)] = sum;
  }
  for (double& c : cdf) c /= sum;
  cdf.back() = 1.0;
  return cdf;
}

inline Table generate(const Settings& s) {
  Table t;
  t.size = s.size;
  t.e.resize(size_t(s.size) * s.size);
  t.e_avg.resize(size_t(s.size));
  for (int j = 0; j < s.size; ++j) {
    for (int i = 0; i < s.size; ++i)
      t.e[size_t(j) * s.size + i] = float(directional_albedo(
          std::pow(double(i) / (s.size - 1), 2.0), double(j) / (s.size - 1), s.samples));
    t.e_avg[size_t(j)] = float(row_average(&t.e[size_t(j) * s.size], s.size));
    for (double c : ms_cdf_row(&t.e[size_t(j) * s.size], s.size)) t.ms_cdf.push_back(float(c));
  }
  return t;
}

inline std::string header(const Table& t, const Settings& s) {
  using luxel_tables::appendf;
  std::string out;
  std::string command;
  appendf(command,
          "luxel_ggx_albedo --size %d --samples %d --out kernels/shading/ggx_albedo_table.h",
          s.size, s.samples);
  luxel_tables::append_banner(
      out,
      {"ggx_albedo_table.h: GENERATED by luxel_ggx_albedo",
       "(server/tools/make_ggx_albedo_table.cpp), do not edit.", "Regenerate with:"},
      command);
  out +=
      " * Directional albedo E(mu, roughness) of single-scattering GGX with F = 1\n"
      " * (Smith height-correlated G2, alpha = max(roughness^2, 1e-3)) and its\n"
      " * average E_avg(roughness) = 2 int E(mu) mu dmu, for the Kulla-Conty 2017\n"
      " * energy compensation in bsdf.h. lux_ggx_e[j * LUX_GGX_ALBEDO_SIZE + i] is\n"
      " * E at sqrt(mu) = i / (SIZE - 1), roughness = j / (SIZE - 1); interpolate\n"
      " * bilinearly in (sqrt(mu), roughness). lux_ggx_e_avg[j] is the exact\n"
      " * average 2 int E mu dmu of row j's interpolant. lux_ggx_ms_cdf[j * (SIZE - 1)\n"
      " * + i] is the cumulative distribution over the cells of sqrt(mu) that the\n"
      " * compensation lobe is sampled from (shape (1 - E(mu)) mu, exact per cell).\n */\n"
      "#ifndef LUXEL_SHADING_GGX_ALBEDO_TABLE_H\n#define LUXEL_SHADING_GGX_ALBEDO_TABLE_H\n\n";
  appendf(out, "#define LUX_GGX_ALBEDO_SIZE %d\n\n", t.size);
  out +=
      "#if defined(__OPENCL_VERSION__) || defined(__OPENCL_C_VERSION__)\n#define "
      "LUX_GGX_TABLE_QUAL "
      "__constant\n#else\n#define LUX_GGX_TABLE_QUAL static const\n#endif\n\n"
      "LUX_GGX_TABLE_QUAL float lux_ggx_e[LUX_GGX_ALBEDO_SIZE * LUX_GGX_ALBEDO_SIZE] = {\n";
  const size_t size = size_t(t.size), cells = size - 1;
  for (size_t j = 0; j < size; ++j) {
    appendf(out, "    /* roughness %.5f */\n", double(j) / double(cells));
    luxel_tables::append_float_rows(out, &t.e[j * size], size, 6, 9, true);
  }
  out += "};\n\nLUX_GGX_TABLE_QUAL float lux_ggx_e_avg[LUX_GGX_ALBEDO_SIZE] = {\n";
  luxel_tables::append_float_rows(out, t.e_avg.data(), size, 6, 9, true);
  out +=
      "};\n\nLUX_GGX_TABLE_QUAL float lux_ggx_ms_cdf[LUX_GGX_ALBEDO_SIZE * (LUX_GGX_ALBEDO_SIZE - "
      "1)] = {\n";
  for (size_t j = 0; j < size; ++j) {
    appendf(out, "    /* roughness %.5f */\n", double(j) / double(cells));
    luxel_tables::append_float_rows(out, &t.ms_cdf[j * cells], cells, 6, 9, true);
  }
  out += "};\n\n#undef LUX_GGX_TABLE_QUAL\n\n#endif /* LUXEL_SHADING_GGX_ALBEDO_TABLE_H */\n";
  return out;
}

}  // namespace luxel_ggx_albedo

#ifndef LUXEL_GGX_ALBEDO_NO_MAIN
int main(int argc, char** argv) {
  luxel_ggx_albedo::Settings s;
  const char* out_path = nullptr;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    if (a + 1 >= argc) {
      std::fprintf(stderr, "usage: %s [--size N] [--samples N] [--out FILE]\n", argv[0]);
      return 2;
    }
    const char* value = argv[++a];
    const long n = std::strtol(value, nullptr, 10);
    if (arg == "--out") {
      out_path = value;
    } else if (arg == "--size" && n >= 2 && n <= 1024) {
      s.size = int(n);
    } else if (arg == "--samples" && n >= 1 && n <= (1 << 24)) {
      s.samples = int(n);
    } else {
      std::fprintf(stderr, "bad option %s %s\n", arg.c_str(), value);
      return 2;
    }
  }
  const std::string text = luxel_ggx_albedo::header(luxel_ggx_albedo::generate(s), s);
  return luxel_tables::write_table(text, out_path) ? 0 : 1;
}
#endif
