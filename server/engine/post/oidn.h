// Intel Open Image Denoise's lightmap filter ("RTLightmap", OIDN API
// documentation "RTLightmap") as the alternative to the a-trous denoiser
// (denoise.h), `settings.denoise = oidn`.
//
//   auto lib = load_oidn();                     // dlopen, once per process
//   if (!lib) ...fall back to a-trous, say lib.status().message()...
//   OidnDenoiser d(*lib.value(), guides);
//   auto out = d.run(rgba, variance, params);
//
// The library is loaded at run time (oidn_api.h says why) from, in order:
// $LUXEL_OIDN_LIBRARY, the prefix deploy/install-deps.sh installs it into
// ($LUXEL_PREFIX or /opt/luxel, under oidn/pyoidn/oidn/lib), the default
// loader path. The filter runs on OIDN's CPU device, on the host.
//
// Lightmap-correct use: the network sees one chart at a time. Each chart is
// cut out at its bounding box; the box's other texels (empty padding, other
// charts) are filled from the chart itself (output/dilate.h, then the chart's
// mean), so neither the black background nor a neighbouring chart's light
// enters the filter. Only the chart's covered texels are written back;
// uncovered ones keep the raw values. Afterwards the filter's change of each
// texel is shrunk by the ratio of the raw map's noise to the change
// (OidnBlend::kShrink), so a converged bake comes out unchanged and the
// filter's bias shrinks with the noise.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "common/status.h"
#include "post/denoise_guides.h"
#include "post/oidn_api.h"

namespace luxel::pipeline {

struct OidnLibrary {
  std::string path;  // what dlopen was given
  int version = 0;   // the device's "version" (20501 for 2.5.1)
  oidn::NewDeviceFn new_device = nullptr;
  oidn::CommitDeviceFn commit_device = nullptr;
  oidn::GetDeviceErrorFn get_device_error = nullptr;
  oidn::GetDeviceIntFn get_device_int = nullptr;
  oidn::ReleaseDeviceFn release_device = nullptr;
  oidn::NewFilterFn new_filter = nullptr;
  oidn::SetSharedFilterImageFn set_shared_filter_image = nullptr;
  oidn::SetFilterBoolFn set_filter_bool = nullptr;
  oidn::CommitFilterFn commit_filter = nullptr;
  oidn::ExecuteFilterFn execute_filter = nullptr;
  oidn::ReleaseFilterFn release_filter = nullptr;
};

// The process's OIDN, loaded on the first call (never unloaded: its TBB
// threads outlive any one bake). NOT_FOUND names every path tried and why
// each failed; the result of the first call is kept, so a process decides
// once. Thread-safe.
Result<const OidnLibrary*> load_oidn();

// The same search without the cache, for tests that point
// LUXEL_OIDN_LIBRARY elsewhere.
Result<OidnLibrary> load_oidn_uncached();

// How the filtered map is blended back towards the raw one, so that the
// denoised map converges to the raw map as the noise falls.
enum class OidnBlend {
  // Each texel keeps the fraction w = min(1, s2 / d2) of the filter's change
  // of its luminance, s2 the variance of its raw mean and d2 the squared
  // change, both averaged over its covered 3x3 neighbours on the chart
  // (shrink_to_noise in oidn.cpp says why).
  kShrink,
  // Each texel within clamp_standard_errors standard errors of its raw value
  // (clamp_to_standard_errors, the a-trous filter's blend).
  kClamp,
  kNone,  // the network's output as it is (tests and benchmarks only)
};

struct OidnParams {
  OidnBlend blend = OidnBlend::kShrink;
  // kClamp: as DenoiseParams::clamp_standard_errors.
  float clamp_standard_errors = 1.0f;
  // Test hook (the injected error of the leak test): filter each lightmap
  // page as one image, charts dilated into the padding but side by side.
  // Never set by a bake.
  bool whole_pages = false;
  std::string variance_source = "Welford variance of each texel's samples";
};

// What the last run did, for the manifest.
struct OidnRunStats {
  double filter_s = 0;         // inside oidnExecuteFilter, wall seconds
  size_t filtered_texels = 0;  // texels given to the network (crops' areas)
  size_t images = 0;           // oidnExecuteFilter calls (charts, or pages)
  double seconds_per_megatexel() const {
    return filtered_texels ? filter_s / (double(filtered_texels) * 1e-6) : 0.0;
  }
};

class OidnDenoiser {
 public:
  // `guides` of the whole atlas (`pages` pages stacked vertically).
  OidnDenoiser(const OidnLibrary& lib, DenoiseGuides guides, int pages);
  ~OidnDenoiser();
  OidnDenoiser(const OidnDenoiser&) = delete;
  OidnDenoiser& operator=(const OidnDenoiser&) = delete;

  // `rgba`: width * height RGBA texels (A = coverage, passed through);
  // `variance`: variances of the texel means' luminance (for the blend).
  // Returns the filtered RGBA; uncovered texels unchanged; every texel
  // finite and non-negative.
  Result<std::vector<float>> run(const std::vector<float>& rgba, const std::vector<float>& variance,
                                 const OidnParams& params);

  // Spherical-harmonic coefficients of a directional encoding (oidn_directional.cpp):
  // `coefficients` texel-major, `count` (4: L1, 9: L2) x RGB each, lobe-major
  // (BakeResult's layout); `rgba` the irradiance map (its alpha says which
  // texels are covered); `rel_error` each texel's relative standard error.
  // L0 is filtered as HDR, each higher coefficient divided by L0 and by its
  // bound `band_bounds[i]` (max |Y_i| / Y_0 over the sphere, so that it lies
  // in [-1, 1] for non-negative radiance) and filtered in the filter's
  // directional mode, then multiplied back by the filtered L0. L0 and the
  // normalised bands are blended back towards their raw values by
  // params.blend (L0's variance: the texel's relative error times L0; a
  // normalised band's standard error: the texel's relative error).
  Result<std::vector<float>> run_sh(const std::vector<float>& coefficients, int count,
                                    const std::vector<float>& rgba,
                                    const std::vector<float>& rel_error,
                                    const std::vector<float>& band_bounds,
                                    const OidnParams& params);

  const OidnRunStats& stats() const { return stats_; }
  // {"method":"oidn","filter":"RTLightmap",...} for the manifest.
  std::string describe_json(const OidnParams& params) const;

 private:
  // Filters the w x h RGB image in place (`directional`: the filter's mode
  // for normalised coefficients in [-1, 1]).
  Status filter(std::vector<float>& rgb, int w, int h, bool directional);
  // Filters a whole-atlas plane of 3 values per texel in place, one chart at
  // a time (or one page, `whole_pages`), covered texels (alpha of `rgba` > 0)
  // only: the cut-out and fill oidn.h describes.
  Status filter_charts(std::vector<float>& plane, const std::vector<float>& rgba, bool directional,
                       bool whole_pages);
  // params.blend applied to the filtered RGBA `out` of the raw `rgba`.
  void blend(const std::vector<float>& rgba, const std::vector<float>& variance,
             const OidnParams& params, std::vector<float>& out) const;
  const OidnLibrary& lib_;
  DenoiseGuides guides_;
  int pages_ = 1;
  oidn::Device device_ = nullptr;
  OidnRunStats stats_;
};

}  // namespace luxel::pipeline
