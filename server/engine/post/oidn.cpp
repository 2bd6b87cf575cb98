#include "post/oidn.h"

#include <dlfcn.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>

#include "common/clock.h"
#include "output/dilate.h"
#include "post/denoise.h"

namespace luxel::pipeline {
namespace {

// The paths load_oidn tries, in order (oidn.h).
std::vector<std::string> oidn_candidates() {
  std::vector<std::string> paths;
  if (const char* env = std::getenv("LUXEL_OIDN_LIBRARY"); env && *env) {
    // An explicit choice is the only one: falling back to another copy would
    // hide a wrong setting.
    paths.push_back(env);
    return paths;
  }
  const char* prefix = std::getenv("LUXEL_PREFIX");
  paths.push_back(std::string(prefix && *prefix ? prefix : "/opt/luxel") +
                  "/oidn/pyoidn/oidn/lib/libOpenImageDenoise.so.2");
  paths.push_back("libOpenImageDenoise.so.2");  // the default loader path
  return paths;
}

template <typename Fn>
bool bind(void* handle, const char* name, Fn& out) {
  out = reinterpret_cast<Fn>(dlsym(handle, name));
  return out != nullptr;
}

// Opens one candidate and binds the entry points oidn_api.h declares; "" on
// success, else why not.
std::string open_oidn(const std::string& path, OidnLibrary& lib) {
  // The wheel's libraries find each other through their RPATH
  // ($ORIGIN/../lib). Its libtbb.so.12 is not the one used when Embree has
  // already loaded Debian's (same SONAME: the loader reuses it); OIDN runs on
  // that one (oidn_test does). RTLD_LOCAL keeps OIDN's symbols out of the
  // global scope.
  void* h = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!h) {
    const char* e = dlerror();
    return e ? e : "dlopen failed";
  }
  lib.path = path;
  const bool ok = bind(h, "oidnNewDevice", lib.new_device) &&
                  bind(h, "oidnCommitDevice", lib.commit_device) &&
                  bind(h, "oidnGetDeviceError", lib.get_device_error) &&
                  bind(h, "oidnGetDeviceInt", lib.get_device_int) &&
                  bind(h, "oidnReleaseDevice", lib.release_device) &&
                  bind(h, "oidnNewFilter", lib.new_filter) &&
                  bind(h, "oidnSetSharedFilterImage", lib.set_shared_filter_image) &&
                  bind(h, "oidnSetFilterBool", lib.set_filter_bool) &&
                  bind(h, "oidnCommitFilter", lib.commit_filter) &&
                  bind(h, "oidnExecuteFilter", lib.execute_filter) &&
                  bind(h, "oidnReleaseFilter", lib.release_filter);
  if (!ok) {
    const char* e = dlerror();
    dlclose(h);
    return std::string("not an Open Image Denoise 2 library: ") + (e ? e : "missing symbol");
  }
  // A device proves the core and the CPU module load too (they are opened
  // lazily by the library), and gives the version.
  oidn::Device d = lib.new_device(oidn::kDeviceCpu);
  std::string why;
  if (d) {
    lib.commit_device(d);
    const char* msg = nullptr;
    if (lib.get_device_error(d, &msg) != oidn::kErrorNone)
      why = std::string("no CPU device: ") + (msg ? msg : "unknown error");
    else
      lib.version = lib.get_device_int(d, "version");
    lib.release_device(d);
  } else {
    why = "no CPU device";
  }
  if (!why.empty()) dlclose(h);  // a usable library is never closed (oidn.h)
  return why;
}

// The estimate that blends the network's output f back towards the raw mean r
// of each texel (OidnBlend::kShrink): out = r + w (f - r). With the raw
// mean's noise of variance s2 and the filter's bias b at the texel (its own
// noise neglected), the squared error (1 - w)^2 s2 + w^2 b^2 is least at
// w = s2 / (s2 + b^2), the Wiener (James-Stein) shrinkage factor, and the
// expected squared change E[(f - r)^2] is s2 + b^2, so w = s2 / d2. Both are
// averaged over the texel's covered 3x3 neighbours on its chart, since one
// texel's change is a single noisy draw. Where the filter only removes noise
// (d2 ~ s2) it keeps the whole change; where it moves texels by more than the
// noise (a gradient or a shadow it blurs) it keeps a fraction that falls with
// the noise, so a converged map is returned unchanged. Compared with clamping
// every change at one standard error (kClamp), it filters more on flat noise
// and less where the filter is biased.
void shrink_to_noise(const std::vector<float>& rgba, const std::vector<float>& variance,
                     const std::vector<uint32_t>& chart, int width, int height,
                     std::vector<float>& out) {
  auto lum = [](const float* c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; };
  const size_t texels = size_t(width) * size_t(height);
  std::vector<double> d2(texels, 0.0);
  for (size_t t = 0; t < texels; ++t)
    if (rgba[t * 4 + 3] > 0.0f) {
      const double d = lum(&out[t * 4]) - lum(&rgba[t * 4]);
      d2[t] = d * d;
    }
  const std::vector<float> filtered = out;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const size_t t = size_t(y) * size_t(width) + size_t(x);
      if (!(rgba[t * 4 + 3] > 0.0f)) continue;
      double s2 = 0, change = 0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int qx = x + dx, qy = y + dy;
          if (qx < 0 || qy < 0 || qx >= width || qy >= height) continue;
          const size_t q = size_t(qy) * size_t(width) + size_t(qx);
          if (!(rgba[q * 4 + 3] > 0.0f) || chart[q] != chart[t]) continue;
          s2 += std::max(0.0f, variance[q]);
          change += d2[q];
        }
      const double w = change > s2 ? s2 / change : 1.0;
      for (int c = 0; c < 3; ++c)
        out[t * 4 + c] = rgba[t * 4 + c] + float(w) * (filtered[t * 4 + c] - rgba[t * 4 + c]);
    }
}

}  // namespace

// AddressSanitizer aborts the process when a library is dlopened with
// RTLD_DEEPBIND (google/sanitizers#611), and the TBB that OIDN runs on opens
// its topology helper (libtbbbind) that way. A sanitizer build therefore never
// loads OIDN: it denoises with a-trous and says why, like a machine without
// the library.
#if defined(__SANITIZE_ADDRESS__)
#define LUXEL_OIDN_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define LUXEL_OIDN_UNDER_ASAN 1
#endif
#endif

Result<OidnLibrary> load_oidn_uncached() {
  std::string tried;
  for (const std::string& path : oidn_candidates()) {
#ifdef LUXEL_OIDN_UNDER_ASAN
    tried += (tried.empty() ? "" : "; ") + path +
             ": not loaded in an AddressSanitizer build (OIDN's TBB dlopens libtbbbind with "
             "RTLD_DEEPBIND, which the sanitizer refuses)";
    continue;
#endif
    OidnLibrary lib;
    const std::string why = open_oidn(path, lib);
    if (why.empty()) return lib;
    tried += (tried.empty() ? "" : "; ") + why;
  }
  return not_found(tried);
}

Result<const OidnLibrary*> load_oidn() {
  static std::once_flag once;
  static Result<OidnLibrary> loaded = not_found("not loaded");
  std::call_once(once, [] { loaded = load_oidn_uncached(); });
  if (!loaded) return loaded.status();
  return &loaded.value();
}

OidnDenoiser::OidnDenoiser(const OidnLibrary& lib, DenoiseGuides guides, int pages)
    : lib_(lib), guides_(std::move(guides)), pages_(std::max(pages, 1)) {}

OidnDenoiser::~OidnDenoiser() {
  if (device_) lib_.release_device(device_);
}

Status OidnDenoiser::filter(std::vector<float>& rgb, int w, int h, bool directional) {
  if (!device_) {
    device_ = lib_.new_device(oidn::kDeviceCpu);
    if (!device_) return unavailable("oidn: no CPU device");
    lib_.commit_device(device_);
  }
  auto error = [&](const char* what) -> Status {
    const char* msg = nullptr;
    if (lib_.get_device_error(device_, &msg) == oidn::kErrorNone) return Status::ok();
    return internal_error(strprintf("oidn %s: %s", what, msg ? msg : "unknown error"));
  };
  LUXEL_RETURN_IF_ERROR(error("device"));
  // "RTLightmap": HDR irradiance in, the same out, or with `directional`
  // normalised directional coefficients in [-1, 1] (oidn_directional.cpp);
  // in-place is allowed ("Filters": output may alias an input).
  oidn::Filter f = lib_.new_filter(device_, "RTLightmap");
  if (!f) return error("new filter");
  lib_.set_shared_filter_image(f, "color", rgb.data(), oidn::kFormatFloat3, size_t(w), size_t(h), 0,
                               0, 0);
  lib_.set_shared_filter_image(f, "output", rgb.data(), oidn::kFormatFloat3, size_t(w), size_t(h),
                               0, 0, 0);
  lib_.set_filter_bool(f, "directional", directional);
  lib_.commit_filter(f);
  Status s = error("commit");
  if (s.is_ok()) {
    const auto t = std::chrono::steady_clock::now();
    lib_.execute_filter(f);
    stats_.filter_s += seconds_since(t);
    s = error("execute");
  }
  lib_.release_filter(f);
  stats_.filtered_texels += size_t(w) * size_t(h);
  ++stats_.images;
  return s;
}

Status OidnDenoiser::filter_charts(std::vector<float>& plane, const std::vector<float>& rgba,
                                   bool directional, bool whole_pages) {
  const int width = guides_.width, height = guides_.height;
  auto covered = [&](size_t t) { return rgba[t * 4 + 3] > 0.0f; };
  // Each piece's margin and the narrowest chart filtered (why: below).
  static constexpr int kMargin = 2, kMinSide = 3;
  // The pieces to filter: one per chart (its bounding box), or per page.
  struct Crop {
    int x0, y0, x1, y1;  // inclusive, in the atlas
    int mx = 0, my = 0;  // where its padded box starts in the mosaic
    int padded_w() const { return x1 - x0 + 1 + 2 * kMargin; }
    int padded_h() const { return y1 - y0 + 1 + 2 * kMargin; }
  };
  std::map<uint32_t, Crop> crops;
  const int page_h = height / pages_;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const size_t t = size_t(y) * size_t(width) + size_t(x);
      if (!covered(t)) continue;
      const uint32_t key = whole_pages ? uint32_t(y / page_h) : guides_.chart[t];
      auto [it, fresh] = crops.try_emplace(key, Crop{x, y, x, y});
      if (fresh) continue;
      Crop& c = it->second;
      c.x0 = std::min(c.x0, x), c.x1 = std::max(c.x1, x);
      c.y0 = std::min(c.y0, y), c.y1 = std::max(c.y1, y);
    }
  if (crops.empty()) return Status::ok();
  // Every piece is padded by a margin of its own light (dilation,
  // output/dilate.h: thesis section 6.4.1's padding fill; the piece's mean
  // where dilation does not reach) and the padded pieces are packed side by
  // side into one image, so one filter call serves every chart: the call's
  // fixed cost dominated on atlases of thousands of small charts (3.9 s of a
  // 4-s gas-station bake at 128^2 when each chart was its own call). A
  // chart's own texels are then at least two margins from any other chart's,
  // with its own light between (oidn_test's leak check measures what still
  // crosses). The margin is kMargin texels: measured against converged
  // references at 4-64 spp (docs/accuracy.md "Open Image Denoise"), 2 texels
  // gave the same or lower error than the half-side margins of up to 8 used
  // before, and 1 texel a higher one on the sky courtyard, while the filter's
  // cost follows the mosaic's area. Charts narrower than kMinSide texels are
  // not filtered (their texels stay raw): a network that sees a chart of one
  // or two texels across can only average it with what surrounds it.
  std::vector<Crop*> order;
  size_t area = 0;
  int widest = 0;
  for (auto it = crops.begin(); it != crops.end();) {
    Crop& c = it->second;
    if (!whole_pages && std::min(c.x1 - c.x0 + 1, c.y1 - c.y0 + 1) < kMinSide) {
      it = crops.erase(it);
      continue;
    }
    order.push_back(&c);
    const int pw = c.padded_w(), ph = c.padded_h();
    area += size_t(pw) * size_t(ph);
    widest = std::max(widest, pw);
    ++it;
  }
  if (order.empty()) return Status::ok();
  // Shelf packing, tallest first (ties by position, so the layout and the
  // filtered bits are deterministic).
  std::stable_sort(order.begin(), order.end(),
                   [](const Crop* a, const Crop* b) { return a->padded_h() > b->padded_h(); });
  const int mosaic_w = std::max(widest, int(std::ceil(std::sqrt(double(area) * 1.15))));
  int shelf_x = 0, shelf_y = 0, shelf_h = 0;
  for (Crop* c : order) {
    const int pw = c->padded_w(), ph = c->padded_h();
    if (shelf_x + pw > mosaic_w) shelf_y += shelf_h, shelf_x = 0, shelf_h = 0;
    c->mx = shelf_x, c->my = shelf_y;
    shelf_x += pw;
    shelf_h = std::max(shelf_h, ph);
  }
  const int mosaic_h = shelf_y + shelf_h;
  output::Image mosaic = output::make_image(mosaic_w, mosaic_h, 4);
  output::Image mosaic_cover = output::make_image(mosaic_w, mosaic_h, 1);
  auto mine_of = [&](uint32_t key) {
    return [&, key](size_t t) {
      return covered(t) && (whole_pages ? uint32_t(int(t / size_t(width)) / page_h) == key
                                        : guides_.chart[t] == key);
    };
  };
  for (const auto& [key, c] : crops) {
    const auto mine = mine_of(key);
    const int pw = c.padded_w(), ph = c.padded_h();
    // The padded piece with only this chart's texels marked covered, dilated
    // into the rest. Channel 3 marks what holds a value: 1 on the chart, and
    // dilation carries the 1 to the texels it fills.
    output::Image img = output::make_image(pw, ph, 4), cover = output::make_image(pw, ph, 1);
    double sum[3] = {0, 0, 0};
    size_t n = 0;
    for (int y = c.y0; y <= c.y1; ++y)
      for (int x = c.x0; x <= c.x1; ++x) {
        const size_t t = size_t(y) * size_t(width) + size_t(x);
        if (!mine(t)) continue;
        const int px = x - c.x0 + kMargin, py = y - c.y0 + kMargin;
        for (int k = 0; k < 3; ++k) {
          img.at(px, py, k) = plane[t * 3 + size_t(k)];
          sum[k] += plane[t * 3 + size_t(k)];
        }
        img.at(px, py, 3) = 1.0f;
        cover.at(px, py, 0) = 1.0f;
        ++n;
      }
    LUXEL_RETURN_IF_ERROR(output::dilate(img, cover, kMargin + 2));
    for (int y = 0; y < ph; ++y)
      for (int x = 0; x < pw; ++x) {
        const bool filled = img.at(x, y, 3) > 0.0f;
        for (int k = 0; k < 3; ++k)
          mosaic.at(c.mx + x, c.my + y, k) =
              filled ? img.at(x, y, k) : float(sum[k] / double(std::max<size_t>(n, 1)));
        mosaic_cover.at(c.mx + x, c.my + y, 0) = 1.0f;
      }
  }
  // The shelves' leftover corners: the nearest piece's light, else black.
  LUXEL_RETURN_IF_ERROR(output::dilate(mosaic, mosaic_cover, 2 * kMargin));
  std::vector<float> rgb(size_t(mosaic_w) * size_t(mosaic_h) * 3);
  for (int y = 0; y < mosaic_h; ++y)
    for (int x = 0; x < mosaic_w; ++x)
      for (int k = 0; k < 3; ++k)
        rgb[(size_t(y) * size_t(mosaic_w) + size_t(x)) * 3 + size_t(k)] = mosaic.at(x, y, k);
  LUXEL_RETURN_IF_ERROR(filter(rgb, mosaic_w, mosaic_h, directional));
  for (const auto& [key, c] : crops) {
    const auto mine = mine_of(key);
    for (int y = c.y0; y <= c.y1; ++y)
      for (int x = c.x0; x <= c.x1; ++x) {
        const size_t t = size_t(y) * size_t(width) + size_t(x);
        if (!mine(t)) continue;
        const size_t m = size_t(c.my + y - c.y0 + kMargin) * size_t(mosaic_w) +
                         size_t(c.mx + x - c.x0 + kMargin);
        for (int k = 0; k < 3; ++k) {
          const float v = rgb[m * 3 + size_t(k)];
          // A non-finite output keeps the input value.
          if (std::isfinite(v)) plane[t * 3 + size_t(k)] = v;
        }
      }
  }
  return Status::ok();
}

Result<std::vector<float>> OidnDenoiser::run(const std::vector<float>& rgba,
                                             const std::vector<float>& variance,
                                             const OidnParams& params) {
  const int width = guides_.width, height = guides_.height;
  const size_t texels = size_t(width) * size_t(height);
  if (rgba.size() != texels * 4 || variance.size() != texels || guides_.chart.size() != texels)
    return internal_error("oidn: input does not match the lightmap size");
  stats_ = {};
  std::vector<float> plane(texels * 3);
  for (size_t t = 0; t < texels; ++t)
    for (size_t k = 0; k < 3; ++k) plane[t * 3 + k] = rgba[t * 4 + k];
  LUXEL_RETURN_IF_ERROR(filter_charts(plane, rgba, /*directional=*/false, params.whole_pages));
  std::vector<float> out = rgba;
  for (size_t t = 0; t < texels; ++t) {
    if (!(rgba[t * 4 + 3] > 0.0f)) continue;
    // The network's output is not constrained: irradiance is never negative.
    for (size_t k = 0; k < 3; ++k) out[t * 4 + k] = std::max(plane[t * 3 + k], 0.0f);
  }
  blend(rgba, variance, params, out);
  return out;
}

void OidnDenoiser::blend(const std::vector<float>& rgba, const std::vector<float>& variance,
                         const OidnParams& params, std::vector<float>& out) const {
  switch (params.blend) {
    case OidnBlend::kShrink:
      shrink_to_noise(rgba, variance, guides_.chart, guides_.width, guides_.height, out);
      break;
    case OidnBlend::kClamp:
      if (params.clamp_standard_errors > 0)
        clamp_to_standard_errors(rgba, variance, guides_.chart, guides_.width, guides_.height,
                                 params.clamp_standard_errors, out);
      break;
    case OidnBlend::kNone:
      break;
  }
}

std::string OidnDenoiser::describe_json(const OidnParams& params) const {
  nlohmann::json j = {
      {"method", "oidn"},
      {"filter", "RTLightmap"},
      {"reference", "Intel Open Image Denoise, RTLightmap filter (HDR irradiance)"},
      {"library", lib_.path},
      {"version", lib_.version},
      {"device", "cpu"},
      {"isolation", params.whole_pages
                        ? "per lightmap page, charts dilated into their padding"
                        : "per chart: its bounding box, other texels filled from the chart "
                          "(dilation, then its mean)"},
      {"images", stats_.images},
      {"filtered_texels", stats_.filtered_texels},
      {"filter_seconds", stats_.filter_s},
      {"seconds_per_megatexel", stats_.seconds_per_megatexel()},
      {"variance", params.variance_source},
      {"blend", params.blend == OidnBlend::kShrink
                    ? "each texel keeps min(1, s2/d2) of the filter's change (s2: variance of "
                      "its raw mean, d2: squared change, both over its 3x3 chart neighbours)"
                : params.blend == OidnBlend::kClamp
                    ? strprintf("within %g standard errors of the raw value",
                                double(params.clamp_standard_errors))
                    : std::string("none")}};
  return j.dump();
}

}  // namespace luxel::pipeline
