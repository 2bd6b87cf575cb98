/* The SDK headers must compile as OpenCL C 1.2 (ctest
 * reconstruct_sdk_opencl_c, clang -x cl -fsyntax-only). OpenCL 1.2 has no
 * generic address space, so the caller picks one with LUXEL_PTR. */
#define LUXEL_PTR __global
#include "luxel_ad_specular_lut.h"
#include "luxel_lightmap.h"

__kernel void sdk_check(__global const float* c, __global const float* dirs,
                        __global const float* lut, __global float* out) {
  const size_t i = get_global_id(0);
  const float l0 =
      luxel_ad_lut_sample(lut, LUXEL_AD_LUT_SIZE_NDOTV, LUXEL_AD_LUT_SIZE_ALPHA, 0.5f, 0.3f, 0);
  const float l1 =
      luxel_ad_lut_sample(lut, LUXEL_AD_LUT_SIZE_NDOTV, LUXEL_AD_LUT_SIZE_ALPHA, 0.5f, 0.3f, 1);
  float e = luxel_ad_irradiance(c, 3, dirs, 12, 0.0f, 0.0f, 1.0f) +
            luxel_sh_irradiance(c, 1, 9, 0.0f, 0.0f, 1.0f);
  e += luxel_sg_irradiance(c, 1, dirs, 12, 3.4f, 0.0f, 0.0f, 1.0f);
  e += luxel_sg_specular(c, 1, dirs, 12, 3.4f, 0.0f, 0.0f, 1.0f, 0.0f, 0.6f, 0.8f, 0.3f, 0.04f,
                         1.0f);
  e += luxel_ad_specular(c, 1, dirs, 12, 0.0f, 0.0f, 1.0f, 0.0f, 0.6f, 0.8f, 0.3f, l0, l1, 0.04f,
                         1.0f);
  e += luxel_ad_radiance(c, 1, dirs, 12, 0.0f, 0.0f, 1.0f) +
       luxel_sh_radiance(c, 1, 4, 0.0f, 0.0f, 1.0f);
  e += luxel_sg_radiance(c, 1, dirs, 12, 3.4f, 0.0f, 0.0f, 1.0f);
  /* The shipped tables are __constant arrays in OpenCL C. */
  e += luxel_ad_specular_lut[5] + luxel_ad12_directions[3] + luxel_ad9_directions[2];
  out[i] = e;
}
