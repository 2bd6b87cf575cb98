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
// uncovered ones keep the raw values. Afterwards each texel is held within
// `clamp_standard_errors` standard errors of its raw value, the same blend as
// the a-trous filter (clamp_to_standard_errors), so a converged bake comes out
// unchanged and the filter's bias shrinks with the noise.
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

struct OidnParams {
  // As DenoiseParams::clamp_standard_errors (0: off).
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

  const OidnRunStats& stats() const { return stats_; }
  // {"method":"oidn","filter":"RTLightmap",...} for the manifest.
  std::string describe_json(const OidnParams& params) const;

 private:
  // Filters the w x h RGB image in place.
  Status filter(std::vector<float>& rgb, int w, int h);
  const OidnLibrary& lib_;
  DenoiseGuides guides_;
  int pages_ = 1;
  oidn::Device device_ = nullptr;
  OidnRunStats stats_;
};

}  // namespace luxel::pipeline
