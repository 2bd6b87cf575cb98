// tests/bench/encode: directional encodings of procedural HDR environment maps
// (tests/bench/envmaps.h) in the spirit of the core thesis (Roughton 2019):
//
//   Table A  Figs. 7.5 / 7.8: RMSE against the map of naive projection (§7.2
//            footnote 2), full least squares (Eq. 7.3), progressive least
//            squares (Listing 7.1 / Eq. 7.14-7.15, alpha = 3), full NNLS and
//            progressive NNLS (§7.3.1 clamping) for 12 spherical Gaussian lobes
//            (Eq. 8.2) over the sphere and over the hemisphere (§7.2.1),
//            versus the sample count; the floor is the best possible fit (exact
//            Gram matrix, exact moments).
//   Table B  §7.4 / §8.4.1: diffuse irradiance E(n) reconstructed from radiance
//            coefficients (SH L1/L2, SG 9/12 with Hill's fit, Ambient Dice 9/12
//            with Eq. 8.14/8.15) against the quadrature of the map, relative
//            RMSE over a set of normals.
//   Table C  §7.3.1 stability: correlated sample sets (Fig. 7.6), wide
//            overlapping lobes (ill-conditioned Gram matrix), very high
//            dynamic range samples (a 1e5 sun).
//
//   bench_encode [--quick] [--seed S]
//
// Everything is deterministic for a given seed. The signal is the map's
// luminance (Rec. 709 Y); colour would be encoded channel by channel. Sample
// directions are uniform over the fit domain unless a table says otherwise,
// as the solvers assume (solvers.h: each sample weighs domain_area / N).
// Ground truth is a dense quadrature of the piecewise-constant map
// (EnvQuadrature: 2 x 2 Gauss-Legendre points per texel), so the RMSE of a
// fit b over the domain is computed exactly as
//   RMSE^2 = (integral f^2 - 2 b.m + b^T G b) / area
// with G and m the quadrature Gram matrix and moments (Eq. 7.3).
//
// Exit status 1 when any solver fails, returns a non-finite value, or an NNLS
// variant (full or progressive) returns a negative coefficient; the ctest
// smoke entry (--quick) relies on that.
// Over 500 lines: its three tables (thesis Figs. 7.5/7.8, §7.4, §7.3.1) share
// one configuration and one report; the shared solvers' support is
// encode_support.cpp.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "common/clock.h"
#include "common/machine_info.h"
#include "encode/basis.h"
#include "encode/gram.h"
#include "encode/solvers.h"
#include "encode_support.h"
#include "envmaps.h"

using namespace luxel;
using namespace luxel::bench;
namespace enc = luxel::encode;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr float kDefaultSharpness = 3.4f;  // BasisSpec default (§8.3.2)

struct Config {
  bool quick = false;
  uint64_t seed = 1;
  int width = 512, height = 256, supersample = 4, quad_q = 2;
  std::vector<int> counts_a = {32, 64, 128, 256, 512};
  int trials_a = 64;
  int normals = 256;
  int b_low = 256, b_low_trials = 16, b_high = 4096, b_high_trials = 8;
  int c_count = 4096;
  std::vector<int> c_snapshots = {256, 4096, 65536};
};

struct MapData {
  EnvMap map;
  EnvQuadrature sphere, upper;
};

// ---------------------------------------------------------------- Table A

void table_a(const Config& cfg, const std::vector<MapData>& maps) {
  std::printf(
      "#### Table A: solvers vs sample count (Figs. 7.5 / 7.8), 12 spherical Gaussians, lambda = "
      "%.1f\n\n",
      double(kDefaultSharpness));
  std::printf(
      "RMSE of the reconstructed luminance against the map over the fit domain, mean over %d "
      "independent sets of\n"
      "uniform random directions per count (the Halton column: %d Cranley-Patterson rotations of "
      "the Halton (2, 3)\n"
      "sequence). naive = raw moments (b = c, §7.2 footnote 2); LS = discrete least squares (Gram "
      "matrix from the\n"
      "samples); LS exact G = Eq. 7.3 with the exact Gram matrix and Monte Carlo moments; prog. = "
      "Listing 7.1 with\n"
      "Eq. 7.15, alpha = 3, Gauss-Seidel, fp32; NNLS = Lawson-Hanson on the sample Gram matrix; "
      "prog. NNLS = §7.3.1\n"
      "clamping. Floor: best fit with exact Gram matrix and exact moments.\n\n",
      cfg.trials_a, cfg.trials_a);
  for (bool hemi : {false, true}) {
    const enc::SphericalBasis basis = sg_basis(12, kDefaultSharpness, hemi);
    const std::vector<double> g_exact = enc::gram(basis);
    std::printf("**A.%d** %s\n\n", hemi ? 2 : 1,
                hemi ? "hemisphere (§7.2.1): lobes on the hemispherical Fibonacci layout, samples, "
                       "fit and RMSE over "
                       "z >= 0"
                     : "sphere: lobes on the spherical Fibonacci layout, samples, fit and RMSE "
                       "over the sphere");
    std::printf("cond(G) = %.3g (exact Gram matrix, %s)\n\n", condition_number(g_exact, 12),
                hemi ? "quadrature" : "closed form");
    std::vector<std::string> floor_rows, rows;
    for (size_t mi = 0; mi < maps.size(); ++mi) {
      const MapData& md = maps[mi];
      const EnvQuadrature& q = hemi ? md.upper : md.sphere;
      const Truth truth = make_truth(basis, q);
      // gram.h's Gram matrix (closed form or its own quadrature) against the
      // texel quadrature's: both must be the integral of B_i B_j.
      double max_diff = 0.0, max_diag = 0.0;
      for (int i = 0; i < 12; ++i) max_diag = std::max(max_diag, g_exact[size_t(i * 12 + i)]);
      for (size_t k = 0; k < g_exact.size(); ++k)
        max_diff = std::max(max_diff, std::abs(g_exact[k] - truth.gram[k]));
      if (!(max_diff <= 1e-5 * max_diag))
        g_checks.fail(
            strprintf("Gram matrix: gram.h and the texel quadrature differ by %.3g", max_diff));
      const std::string tag = strprintf("A %s %s", md.map.name(), hemi ? "hemisphere" : "sphere");
      const std::vector<double> best_ls =
          exact_least_squares(g_exact, truth.moments, tag + " best LS");
      const std::vector<double> best_nnls = exact_nnls(basis, g_exact, q, tag + " best NNLS");
      floor_rows.push_back(strprintf("| %s | %s | %s | %s |", md.map.name(),
                                     fmt(truth.signal_rms()).c_str(),
                                     fmt(check_value(truth.rmse(best_ls), tag)).c_str(),
                                     fmt(check_value(truth.rmse(best_nnls), tag)).c_str()));

      const enc::Basis plain = solver_basis(basis);
      const enc::Basis exact = solver_basis(basis, &g_exact);
      const enc::ProgressiveOptions prog_ls{3.0f, false, true}, prog_nn{3.0f, true, true};
      for (int n : cfg.counts_a) {
        double sum[7] = {};
        for (int t = 0; t < cfg.trials_a; ++t) {
          const uint64_t seed =
              mix_seed(cfg.seed, 0xA0 + mi, uint64_t(hemi), uint64_t(n) * 1000 + uint64_t(t));
          const std::vector<enc::Sample> s = sample_map(md.map, random_directions(n, seed, hemi));
          Rng rot(seed ^ 0x5bd1e995u);
          const double ou = rot.next_double(), ov = rot.next_double();
          const std::vector<enc::Sample> h = sample_map(md.map, halton_directions(n, hemi, ou, ov));
          const std::string w = strprintf("%s n=%d set %d", tag.c_str(), n, t);
          const std::vector<double> b[7] = {
              checked(enc::solve_naive_projection(plain, s), 12, false, w + " naive"),
              checked(enc::solve_least_squares(plain, s), 12, false, w + " LS"),
              checked(enc::solve_least_squares(exact, s), 12, false, w + " LS exact G"),
              checked(enc::solve_progressive(plain, s, prog_ls), 12, false, w + " progressive LS"),
              checked(enc::solve_nnls(plain, s), 12, true, w + " NNLS"),
              checked(enc::solve_progressive(plain, s, prog_nn), 12, true, w + " progressive NNLS"),
              checked(enc::solve_progressive(plain, h, prog_ls), 12, false,
                      w + " progressive LS Halton"),
          };
          for (int k = 0; k < 7; ++k) sum[k] += check_value(truth.rmse(b[k]), w) / cfg.trials_a;
        }
        rows.push_back(strprintf("| %s | %d | %s | %s | %s | %s | %s | %s | %s |", md.map.name(), n,
                                 fmt(sum[0]).c_str(), fmt(sum[1]).c_str(), fmt(sum[2]).c_str(),
                                 fmt(sum[3]).c_str(), fmt(sum[4]).c_str(), fmt(sum[5]).c_str(),
                                 fmt(sum[6]).c_str()));
      }
    }
    std::printf(
        "| map | signal RMS | floor: best LS fit | floor: best NNLS fit |\n|---|---:|---:|---:|\n");
    for (const std::string& r : floor_rows) std::printf("%s\n", r.c_str());
    std::printf(
        "\n| map | samples | naive | LS | LS exact G | prog. LS | NNLS | prog. NNLS | prog. LS "
        "Halton |\n"
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (const std::string& r : rows) std::printf("%s\n", r.c_str());
    std::printf("\n");
  }
}

// ---------------------------------------------------------------- Table B

struct BasisCase {
  std::string label;
  enc::SphericalBasis basis;
  bool sh = false;
};

void table_b(const Config& cfg, const std::vector<MapData>& maps) {
  std::printf("#### Table B: diffuse irradiance from radiance coefficients (§7.4, §8.4.1)\n\n");
  std::printf(
      "Relative RMSE (%%) of E(n) over %d Fibonacci normals: sqrt(mean (E_rec - E)^2) / mean E, E "
      "by quadrature of\n"
      "the map. exact = best fit with the exact Gram matrix and moments (LS rows: least squares, "
      "SH: exact projection;\n"
      "NNLS row: non-negative least squares). Sampled columns:\n"
      "mean over %d sets of %d and %d sets of %d uniform directions. SH: projection (G = I); SG / "
      "Ambient Dice: full\n"
      "LS (sample Gram matrix), progressive LS and progressive NNLS (alpha = 3). SG lambda = %.1f, "
      "irradiance by Hill's fit; Ambient Dice by\n"
      "Eq. 8.14/8.15. Coefficients per colour channel in brackets.\n\n",
      cfg.normals, cfg.b_low_trials, cfg.b_low, cfg.b_high_trials, cfg.b_high,
      double(kDefaultSharpness));
  using enc::BasisDomain;
  using enc::BasisKind;
  const BasisDomain S = BasisDomain::kSphere, H = BasisDomain::kHemisphere;
  for (bool upper : {false, true}) {
    std::vector<BasisCase> cases;
    if (!upper) {
      cases = {{"SH L1", make_basis(BasisKind::kShL1, 0, 0, S, S), true},
               {"SH L2", make_basis(BasisKind::kShL2, 0, 0, S, S), true},
               {"SG 9", sg_basis(9, kDefaultSharpness, false), false},
               {"SG 12", sg_basis(12, kDefaultSharpness, false), false},
               {"Ambient Dice 12", make_basis(BasisKind::kAmbientDice, 12, 0, S, S), false}};
    } else {
      cases = {{"SH L2", make_basis(BasisKind::kShL2, 0, 0, S, S), true},
               {"SG 12", sg_basis(12, kDefaultSharpness, false), false},
               {"Ambient Dice 12", make_basis(BasisKind::kAmbientDice, 12, 0, S, S), false},
               {"SG 9 hemi", sg_basis(9, kDefaultSharpness, true), false},
               {"Ambient Dice 9", make_basis(BasisKind::kAmbientDice, 9, 0, S, H), false}};
    }
    std::printf(
        "**B.%d** %s\n\n", upper ? 2 : 1,
        upper ? "a texel facing +z: radiance below the horizon is zero, normals on the hemisphere "
                "z >= 0 "
                "only, samples uniform on z >= 0. Sphere-domain bases add a zero sample opposite "
                "each sample "
                "(end of §7.3.1); SG 9 hemi and Ambient Dice 9 (§8.3.1) fit over the hemisphere."
              : "whole map: normals and samples over the whole sphere");
    std::printf("| basis | solver |");
    for (const MapData& md : maps)
      std::printf(" %s exact | %d | %d |", md.map.name(), cfg.b_low, cfg.b_high);
    std::printf("\n|---|---|");
    for (size_t i = 0; i < maps.size(); ++i) std::printf("---:|---:|---:|");
    std::printf("\n");

    const std::vector<Vec3> normals = fibonacci_directions(cfg.normals, upper);
    // Normals within 45 degrees of +z (B.3): a hemisphere Fibonacci set of
    // 4x the size, filtered, so about as many normals as the main set.
    std::vector<Vec3> normals45;
    for (const Vec3& n : fibonacci_directions(4 * cfg.normals, true))
      if (n.z >= 0.70710678f) normals45.push_back(n);
    // Ground-truth irradiance: E(n) = sum_k w_k f_k max(0, n.w_k).
    auto irradiance = [](const EnvQuadrature& q, const std::vector<Vec3>& ns) {
      std::vector<double> e(ns.size(), 0.0);
      for (size_t k = 0; k < q.directions.size(); ++k) {
        const double wf = q.weights[k] * q.values[k];
        const Vec3 d = q.directions[k];
        for (size_t j = 0; j < ns.size(); ++j) {
          const double c = double(dot(ns[j], d));
          if (c > 0.0) e[j] += wf * c;
        }
      }
      return e;
    };
    std::vector<std::vector<double>> truth(maps.size()), truth45(maps.size());
    for (size_t mi = 0; mi < maps.size(); ++mi) {
      truth[mi] = irradiance(upper ? maps[mi].upper : maps[mi].sphere, normals);
      if (upper) truth45[mi] = irradiance(maps[mi].upper, normals45);
    }
    // sqrt(mean (E_rec - E)^2) / mean E over the normal set.
    auto relative_error = [](const enc::SphericalBasis& basis, const std::vector<double>& b,
                             const std::vector<Vec3>& ns, const std::vector<double>& e_true) {
      std::vector<float> c(b.begin(), b.end());
      double sum = 0.0, mean = 0.0;
      for (size_t j = 0; j < ns.size(); ++j) {
        const double e = basis.diffuse_irradiance(c.data(), ns[j]) - e_true[j];
        sum += e * e;
        mean += e_true[j];
      }
      return std::sqrt(sum / double(ns.size())) / (mean / double(ns.size()));
    };
    auto diffuse_error = [&](const enc::SphericalBasis& basis, const std::vector<double>& b,
                             size_t mi) { return relative_error(basis, b, normals, truth[mi]); };
    std::vector<std::string> rows45;

    for (const BasisCase& bc : cases) {
      const std::vector<double> g_exact = enc::gram(bc.basis);
      const enc::Basis sb = solver_basis(bc.basis);
      const bool sphere_fit = bc.basis.spec().fit_domain == S;
      const bool mirror = upper && sphere_fit;  // zero samples below the horizon
      const int solvers = bc.sh ? 1 : 3;
      for (int sv = 0; sv < solvers; ++sv) {
        const char* solver_name =
            bc.sh ? "projection" : (sv == 0 ? "LS" : (sv == 1 ? "prog. LS" : "prog. NNLS"));
        std::printf("| %s [%d] | %s |", bc.label.c_str(), bc.basis.size(), solver_name);
        for (size_t mi = 0; mi < maps.size(); ++mi) {
          const MapData& md = maps[mi];
          const std::string tag =
              strprintf("B %s %s %s", md.map.name(), bc.label.c_str(), solver_name);
          const std::vector<double> m = exact_moments(bc.basis, upper ? md.upper : md.sphere);
          const EnvQuadrature& q = upper ? md.upper : md.sphere;
          const std::vector<double> best = bc.sh ? m
                                           : sv < 2
                                               ? exact_least_squares(g_exact, m, tag + " exact")
                                               : exact_nnls(bc.basis, g_exact, q, tag + " exact");
          std::printf(" %s |", pct(check_value(diffuse_error(bc.basis, best, mi), tag)).c_str());
          if (upper && sv == 0) {
            if (mi == 0)
              rows45.push_back(strprintf("| %s [%d] |", bc.label.c_str(), bc.basis.size()));
            rows45.back() += strprintf(
                " %s |", pct(relative_error(bc.basis, best, normals45, truth45[mi])).c_str());
          }
          for (int which = 0; which < 2; ++which) {
            const int n = which == 0 ? cfg.b_low : cfg.b_high;
            const int trials = which == 0 ? cfg.b_low_trials : cfg.b_high_trials;
            double err = 0.0;
            for (int t = 0; t < trials; ++t) {
              const uint64_t seed =
                  mix_seed(cfg.seed, 0xB0 + mi, uint64_t(upper), uint64_t(n) * 1000 + uint64_t(t));
              std::vector<enc::Sample> s = sample_map(md.map, random_directions(n, seed, upper));
              if (mirror) {
                // A zero sample right after each true one (interleaved: the
                // progressive encoder must not see all zeros at the end).
                std::vector<enc::Sample> both;
                both.reserve(2 * s.size());
                for (const enc::Sample& a : s) {
                  both.push_back(a);
                  both.push_back({{-a.direction[0], -a.direction[1], -a.direction[2]}, 0.0});
                }
                s = std::move(both);
              }
              const std::string w = strprintf("%s n=%d set %d", tag.c_str(), n, t);
              std::vector<double> b;
              if (bc.sh) {
                b = checked(enc::solve_naive_projection(sb, s), bc.basis.size(), false, w);
              } else if (sv == 0) {
                b = checked(enc::solve_least_squares(sb, s), bc.basis.size(), false, w);
              } else if (sv == 1) {
                b = checked(enc::solve_progressive(sb, s, {3.0f, false, true}), bc.basis.size(),
                            false, w);
              } else {
                b = checked(enc::solve_progressive(sb, s, {3.0f, true, true}), bc.basis.size(),
                            true, w);
              }
              err += check_value(diffuse_error(bc.basis, b, mi), w) / trials;
            }
            std::printf(" %s |", pct(err).c_str());
          }
        }
        std::printf("\n");
      }
    }
    std::printf("\n");
    if (upper) {
      std::printf(
          "**B.3** the same texel, best fits only, %zu normals within 45 degrees of +z (the range "
          "normal maps\n"
          "usually perturb a normal in)\n\n| basis |",
          normals45.size());
      for (const MapData& md : maps) std::printf(" %s exact |", md.map.name());
      std::printf("\n|---|");
      for (size_t i = 0; i < maps.size(); ++i) std::printf("---:|");
      std::printf("\n");
      for (const std::string& r : rows45) std::printf("%s\n", r.c_str());
      std::printf("\n");
    }
  }
}

// ---------------------------------------------------------------- Table C

void table_c(const Config& cfg, const std::vector<MapData>& maps) {
  std::printf("#### Table C: stability (§7.3.1)\n\n");
  const enc::ProgressiveOptions prog_ls{3.0f, false, true}, prog_nn{3.0f, true, true};

  // (i) Correlated sample sets vs sequences (Fig. 7.6).
  {
    const enc::SphericalBasis basis = sg_basis(12, kDefaultSharpness, false);
    const enc::Basis sb = solver_basis(basis);
    std::printf(
        "**C.1** sample order (Fig. 7.6): 12 SG (lambda %.1f) over the sphere, %d samples\n\n"
        "Progressive LS against the full LS solve on the same samples; distance = function-space "
        "RMS of the\n"
        "difference / signal RMS. Hammersley: the set in index order (u1 = (i + 0.5) / N sweeps "
        "pole to pole);\n"
        "random: one uniform random stream; Halton: the plain (2, 3) sequence.\n\n"
        "| map | order | full LS RMSE | prog. LS RMSE | prog. vs full (rel.) | prog. running "
        "residual |\n"
        "|---|---|---:|---:|---:|---:|\n",
        double(kDefaultSharpness), cfg.c_count);
    for (size_t mi = 0; mi < maps.size(); ++mi) {
      const MapData& md = maps[mi];
      const Truth truth = make_truth(basis, md.sphere);
      for (int order = 0; order < 3; ++order) {
        const char* name = order == 0 ? "Hammersley" : (order == 1 ? "random" : "Halton");
        const std::vector<Vec3> dirs =
            order == 0
                ? hammersley_directions(cfg.c_count, false)
                : (order == 1 ? random_directions(cfg.c_count, mix_seed(cfg.seed, 0xC1, mi), false)
                              : halton_directions(cfg.c_count, false));
        const std::vector<enc::Sample> s = sample_map(md.map, dirs);
        const std::string w = strprintf("C.1 %s %s", md.map.name(), name);
        const std::vector<double> ls =
            checked(enc::solve_least_squares(sb, s), 12, false, w + " LS");
        // Through the encoder itself for its running residual.
        enc::ProgressiveEncoder encoder(12, prog_ls);
        std::vector<float> v(12);
        for (const enc::Sample& x : s) {
          basis.evaluate(Vec3{float(x.direction[0]), float(x.direction[1]), float(x.direction[2])},
                         v.data());
          encoder.add_sample(v, float(x.value));
        }
        const std::vector<double> prog(encoder.amplitudes().begin(), encoder.amplitudes().end());
        check_coefficients(prog, false, w + " progressive LS");
        std::printf(
            "| %s | %s | %s | %s | %s | %s |\n", md.map.name(), name, fmt(truth.rmse(ls)).c_str(),
            fmt(truth.rmse(prog)).c_str(),
            fmt(truth.distance(prog, ls) / truth.signal_rms()).c_str(),
            fmt(check_value(encoder.running_residual_rms(), w + " running residual")).c_str());
      }
    }
    std::printf("\n");
  }

  // (ii) Wide, heavily overlapping lobes: an ill-conditioned Gram matrix.
  {
    std::printf(
        "**C.2** wide lobes: 12 SG over the sphere, %d uniform random samples\n\n"
        "cond(G) of the exact (closed-form) Gram matrix; ridge = regularisation the full LS needed "
        "(relative to\n"
        "mean diag G, 0 = none); distance = function-space RMS of prog. LS - full LS over the "
        "signal RMS.\n\n"
        "| lambda | cond(G) | map | floor | LS RMSE | ridge | prog. LS RMSE | prog. vs LS (rel.) | "
        "NNLS RMSE | "
        "prog. NNLS RMSE |\n|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|\n",
        cfg.c_count);
    for (float lambda : {0.5f, 1.0f, kDefaultSharpness}) {
      const enc::SphericalBasis basis = sg_basis(12, lambda, false);
      const std::vector<double> g_exact = enc::gram(basis);
      const double cond = condition_number(g_exact, 12);
      double mean_diag = 0.0;
      for (int i = 0; i < 12; ++i) mean_diag += g_exact[size_t(i * 12 + i)] / 12.0;
      const enc::Basis sb = solver_basis(basis);
      for (size_t mi = 0; mi < maps.size(); ++mi) {
        const MapData& md = maps[mi];
        const Truth truth = make_truth(basis, md.sphere);
        const std::string w = strprintf("C.2 lambda %.1f %s", double(lambda), md.map.name());
        const std::vector<double> best = exact_least_squares(g_exact, truth.moments, w + " best");
        const std::vector<enc::Sample> s =
            sample_map(md.map, random_directions(cfg.c_count, mix_seed(cfg.seed, 0xC2, mi), false));
        const Result<enc::Solution> ls_r = enc::solve_least_squares(sb, s);
        const std::vector<double> ls = checked(ls_r, 12, false, w + " LS");
        const std::vector<double> prog =
            checked(enc::solve_progressive(sb, s, prog_ls), 12, false, w + " prog LS");
        const std::vector<double> nnls = checked(enc::solve_nnls(sb, s), 12, true, w + " NNLS");
        const std::vector<double> prog_n =
            checked(enc::solve_progressive(sb, s, prog_nn), 12, true, w + " prog NNLS");
        const double ridge = ls_r.is_ok() ? ls_r->regularization / mean_diag : NAN;
        std::printf("| %.1f | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n", double(lambda),
                    fmt(cond).c_str(), md.map.name(), fmt(truth.rmse(best)).c_str(),
                    fmt(truth.rmse(ls)).c_str(), ridge == 0.0 ? "0" : fmt(ridge).c_str(),
                    fmt(truth.rmse(prog)).c_str(),
                    fmt(truth.distance(prog, ls) / truth.signal_rms()).c_str(),
                    fmt(truth.rmse(nnls)).c_str(), fmt(truth.rmse(prog_n)).c_str());
      }
    }
    std::printf("\n");
  }

  // (iii) Very high dynamic range: the sunny map (sun 1e5 x the sky).
  {
    const MapData* sunny = nullptr;
    for (const MapData& md : maps)
      if (md.map.kind() == EnvMapKind::kSunny) sunny = &md;
    if (!sunny) return;
    std::printf(
        "**C.3** high dynamic range: the sunny map, 12 SG (lambda %.1f), one uniform random "
        "stream\n\n"
        "The progressive encoders (fp32) see the samples once, in order; the full solves use the "
        "same prefix.\n"
        "sun = samples that hit the sun disc (luminance > 1000); running = "
        "ProgressiveEncoder::running_residual_rms;\n"
        "sample residual = the full solve's RMS residual on the samples; distance = function-space "
        "RMS of\n"
        "progressive - full over the domain (absolute; the signal RMS is in the caption of each "
        "block).\n\n",
        double(kDefaultSharpness));
    for (bool hemi : {true, false}) {
      const enc::SphericalBasis basis = sg_basis(12, kDefaultSharpness, hemi);
      const enc::Basis sb = solver_basis(basis);
      const Truth truth = make_truth(basis, hemi ? sunny->upper : sunny->sphere);
      std::printf("%s (signal RMS %s, floor %s):\n\n", hemi ? "hemisphere z >= 0" : "sphere",
                  fmt(truth.signal_rms()).c_str(),
                  fmt(truth.rmse(exact_least_squares(enc::gram(basis), truth.moments, "C.3 best")))
                      .c_str());
      std::printf(
          "| samples | sun | prog. LS running | LS sample residual | prog. LS vs LS | prog. LS "
          "RMSE | LS RMSE | "
          "prog. NNLS running | NNLS sample residual | prog. NNLS vs NNLS | prog. NNLS RMSE | NNLS "
          "RMSE |\n"
          "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
      const int total = cfg.c_snapshots.back();
      const std::vector<enc::Sample> s = sample_map(
          sunny->map, random_directions(total, mix_seed(cfg.seed, 0xC3, uint64_t(hemi)), hemi));
      enc::ProgressiveEncoder enc_ls(12, prog_ls), enc_nn(12, prog_nn);
      std::vector<float> v(12);
      int sun_hits = 0;
      size_t next = 0;
      for (int k = 0; k < total; ++k) {
        const enc::Sample& x = s[size_t(k)];
        basis.evaluate(Vec3{float(x.direction[0]), float(x.direction[1]), float(x.direction[2])},
                       v.data());
        enc_ls.add_sample(v, float(x.value));
        enc_nn.add_sample(v, float(x.value));
        if (x.value > 1000.0) ++sun_hits;
        if (next < cfg.c_snapshots.size() && k + 1 == cfg.c_snapshots[next]) {
          const int n = k + 1;
          const std::span<const enc::Sample> prefix(s.data(), size_t(n));
          const std::string w = strprintf("C.3 %s n=%d", hemi ? "hemisphere" : "sphere", n);
          const std::vector<double> pl(enc_ls.amplitudes().begin(), enc_ls.amplitudes().end());
          const std::vector<double> pn(enc_nn.amplitudes().begin(), enc_nn.amplitudes().end());
          check_coefficients(pl, false, w + " progressive LS");
          check_coefficients(pn, true, w + " progressive NNLS");
          const Result<enc::Solution> ls_r = enc::solve_least_squares(sb, prefix);
          const Result<enc::Solution> nn_r = enc::solve_nnls(sb, prefix);
          const std::vector<double> ls = checked(ls_r, 12, false, w + " LS");
          const std::vector<double> nn = checked(nn_r, 12, true, w + " NNLS");
          std::printf("| %d | %d | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n", n,
                      sun_hits, fmt(check_value(enc_ls.running_residual_rms(), w)).c_str(),
                      fmt(ls_r.is_ok() ? ls_r->residual_rms : NAN).c_str(),
                      fmt(truth.distance(pl, ls)).c_str(), fmt(truth.rmse(pl)).c_str(),
                      fmt(truth.rmse(ls)).c_str(),
                      fmt(check_value(enc_nn.running_residual_rms(), w)).c_str(),
                      fmt(nn_r.is_ok() ? nn_r->residual_rms : NAN).c_str(),
                      fmt(truth.distance(pn, nn)).c_str(), fmt(truth.rmse(pn)).c_str(),
                      fmt(truth.rmse(nn)).c_str());
          ++next;
        }
      }
      std::printf("\n");
    }
  }
}

void usage() {
  std::fprintf(stderr, "usage: bench_encode [--quick] [--seed S]\n");
}

}  // namespace

int main(int argc, char** argv) {
  Config cfg;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) {
      cfg.quick = true;
    } else if (std::strcmp(argv[i], "--seed") == 0 && i + 1 < argc) {
      cfg.seed = std::strtoull(argv[++i], nullptr, 10);
    } else {
      usage();
      return 2;
    }
  }
  if (cfg.quick) {
    cfg.width = 256;
    cfg.height = 128;
    cfg.supersample = 2;
    cfg.counts_a = {32, 128, 512};
    cfg.trials_a = 4;
    cfg.normals = 64;
    cfg.b_low_trials = 2;
    cfg.b_high = 1024;
    cfg.b_high_trials = 1;
    cfg.c_count = 1024;
    cfg.c_snapshots = {256, 4096, 16384};
  }
  const auto t0 = std::chrono::steady_clock::now();

  std::printf("bench_encode%s, seed %llu\n\n", cfg.quick ? " --quick" : "",
              (unsigned long long)cfg.seed);
  std::printf("machine: %s\n\n", describe(machine_info()).c_str());
  std::vector<MapData> maps;
  std::printf(
      "Environment maps: %d x %d equirectangular texels (area averages of %d x %d analytic "
      "samples), nearest lookup;\n"
      "quadrature %d x %d Gauss-Legendre points per texel.\n\n| map | min luminance | max "
      "luminance | dynamic range | "
      "mean luminance (sphere) |\n|---|---:|---:|---:|---:|\n",
      cfg.width, cfg.height, cfg.supersample, cfg.supersample, cfg.quad_q, cfg.quad_q);
  for (EnvMapKind kind : EnvMap::all_kinds()) {
    MapData md{EnvMap::generate(kind, cfg.width, cfg.height, cfg.supersample), {}, {}};
    md.sphere = EnvQuadrature::build(md.map, false, cfg.quad_q);
    md.upper = EnvQuadrature::build(md.map, true, cfg.quad_q);
    double mean = 0.0;
    for (size_t k = 0; k < md.sphere.weights.size(); ++k)
      mean += md.sphere.weights[k] * md.sphere.values[k];
    mean /= md.sphere.area;
    if (std::abs(md.sphere.area - 4.0 * kPi) > 1e-9 || std::abs(md.upper.area - 2.0 * kPi) > 1e-9)
      g_checks.fail(strprintf("%s: quadrature weights sum to %.12g / %.12g", md.map.name(),
                              md.sphere.area, md.upper.area));
    std::printf("| %s | %s | %s | %s | %s |\n", md.map.name(), fmt(md.map.min_luminance()).c_str(),
                fmt(md.map.max_luminance()).c_str(),
                fmt(double(md.map.max_luminance()) / double(md.map.min_luminance())).c_str(),
                fmt(mean).c_str());
    maps.push_back(std::move(md));
  }
  std::printf("\n");

  table_a(cfg, maps);
  table_b(cfg, maps);
  table_c(cfg, maps);

  const double seconds = seconds_since(t0);
  std::printf("checks: %ld solutions, %ld failures; %.1f s\n", g_checks.solutions,
              g_checks.failures, seconds);
  for (const std::string& m : g_checks.messages)
    std::fprintf(stderr, "bench_encode: FAILED %s\n", m.c_str());
  return g_checks.failures == 0 ? 0 : 1;
}
