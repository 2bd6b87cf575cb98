/* The SDK headers must compile as C99 (they are shipped to C engines too):
 * this translation unit is built by the C compiler with warnings enabled and
 * called from diffuse_test.cpp to check it computes what C++ computes. */
#include "luxel_ad_specular_lut.h"
#include "luxel_lightmap.h"

float luxel_c_compile_check(const float* coeffs, float nx, float ny, float nz);

float luxel_c_compile_check(const float* coeffs, float nx, float ny, float nz) {
  /* Touch every entry point once so each is compiled as C. */
  const float lut0 = luxel_ad_lut_sample(luxel_ad_specular_lut, LUXEL_AD_LUT_SIZE_NDOTV,
                                         LUXEL_AD_LUT_SIZE_ALPHA, 0.5f, 0.5f, 0);
  const float lut1 = luxel_ad_lut_sample(luxel_ad_specular_lut, LUXEL_AD_LUT_SIZE_NDOTV,
                                         LUXEL_AD_LUT_SIZE_ALPHA, 0.5f, 0.5f, 1);
  float unused = luxel_ad_specular(coeffs, 1, luxel_ad12_directions, 12, nx, ny, nz, 0.0f, 0.0f,
                                   1.0f, 0.5f, lut0, lut1, 0.04f, 1.0f);
  unused += luxel_sg_specular(coeffs, 1, luxel_ad12_directions, 12, 3.4f, nx, ny, nz, 0.0f, 0.0f,
                              1.0f, 0.5f, 0.04f, 1.0f);
  unused +=
      luxel_sh_irradiance(coeffs, 1, 9, nx, ny, nz) + luxel_sh_radiance(coeffs, 1, 9, nx, ny, nz);
  unused += luxel_sg_irradiance(coeffs, 1, luxel_ad9_directions, 9, 3.4f, nx, ny, nz);
  unused += luxel_sg_radiance(coeffs, 1, luxel_ad9_directions, 9, 3.4f, nx, ny, nz);
  unused += luxel_ad_radiance(coeffs, 1, luxel_ad9_directions, 9, nx, ny, nz);
  {
    /* Light probes: a parse that fails (no bytes), then a query. */
    LuxelProbeSet set;
    float rgb[3];
    if (luxel_probes_parse(coeffs, 0, &set) == 0)
      unused += luxel_probes_irradiance(&set, 0.0f, 0.0f, 0.0f, nx, ny, nz, 1, rgb);
  }
  (void)unused;
  return luxel_ad_irradiance(coeffs, 1, luxel_ad12_directions, 12, nx, ny, nz);
}
