// The committed kernels/shading/ggx_albedo_table.h against a fresh
// in-process regeneration with the generator's own settings (it takes about
// a second): the committed file must be exactly what luxel_ggx_albedo
// (server/tools/make_ggx_albedo_table.cpp) writes. Also
// checks the table against known properties of single-scattering GGX.
#include "kernels/shading/ggx_albedo_table.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#define LUXEL_GGX_ALBEDO_NO_MAIN
#include "make_ggx_albedo_table.cpp"  // the generator's functions, without main

namespace {

namespace gen = luxel_ggx_albedo;

TEST(GgxAlbedoTable, CommittedTableIsTheGeneratorsOutput) {
  const gen::Settings s;  // the defaults the committed header records
  ASSERT_EQ(s.size, LUX_GGX_ALBEDO_SIZE);
  const gen::Table t = gen::generate(s);
  // Printed with %#.9g, every float round-trips exactly.
  int differing = 0;
  for (size_t k = 0; k < t.e.size(); ++k) differing += t.e[k] != lux_ggx_e[k];
  for (size_t k = 0; k < t.e_avg.size(); ++k) differing += t.e_avg[k] != lux_ggx_e_avg[k];
  EXPECT_EQ(differing, 0) << "regenerate with: luxel_ggx_albedo --out "
                             "kernels/shading/ggx_albedo_table.h";
  // And the text itself, so comments and layout cannot drift either.
  FILE* f = std::fopen(LUXEL_GGX_ALBEDO_TABLE_PATH, "rb");
  ASSERT_NE(f, nullptr) << LUXEL_GGX_ALBEDO_TABLE_PATH;
  std::string committed;
  char buf[4096];
  for (size_t n; (n = std::fread(buf, 1, sizeof buf, f)) > 0;) committed.append(buf, n);
  std::fclose(f);
  EXPECT_EQ(committed, gen::header(t, s));
}

TEST(GgxAlbedoTable, SingleScatteringLosesEnergyWithRoughness) {
  // E <= 1 everywhere, ~1 for a smooth surface away from grazing, and E_avg
  // strictly decreasing with roughness (the loss Kulla-Conty compensates).
  for (int k = 0; k < LUX_GGX_ALBEDO_SIZE * LUX_GGX_ALBEDO_SIZE; ++k) {
    EXPECT_LE(lux_ggx_e[k], 1.0f + 1e-6f) << k;
    EXPECT_GT(lux_ggx_e[k], 0.0f) << k;
  }
  for (int i = 8; i < LUX_GGX_ALBEDO_SIZE; ++i) EXPECT_GT(lux_ggx_e[i], 0.999f) << i;
  for (int j = 1; j < LUX_GGX_ALBEDO_SIZE; ++j)
    EXPECT_LE(lux_ggx_e_avg[j], lux_ggx_e_avg[j - 1] + 1e-6f) << j;
  // Roughness 1 (alpha 1) loses more than half on average.
  EXPECT_LT(lux_ggx_e_avg[LUX_GGX_ALBEDO_SIZE - 1], 0.5f);
}

TEST(GgxAlbedoTable, AverageIsTheIntegralOfTheInterpolatedRow) {
  // E_avg = 2 int E mu dmu of the row's interpolant (linear in sqrt(mu)), by a fine midpoint
  // rule: the compensation lobe's albedo is then exactly 1 - E(mu_o).
  for (int j : {0, 10, 20, LUX_GGX_ALBEDO_SIZE - 1}) {
    const int n = 1 << 16;
    double sum = 0.0;
    for (int k = 0; k < n; ++k) {
      const double mu = (k + 0.5) / n, x = std::sqrt(mu) * (LUX_GGX_ALBEDO_SIZE - 1);
      const int i = std::min(int(x), LUX_GGX_ALBEDO_SIZE - 2);
      const float* row = &lux_ggx_e[j * LUX_GGX_ALBEDO_SIZE];
      sum += 2.0 * mu * (row[i] + (x - i) * (row[i + 1] - row[i])) / n;
    }
    EXPECT_NEAR(sum, lux_ggx_e_avg[j], 1e-6) << "row " << j;
  }
}

}  // namespace
