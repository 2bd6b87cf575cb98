#include "bake/host_memory.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <utility>
#include <vector>

#include "post/denoise.h"
#include "shards/checkpoint.h"

namespace luxel::pipeline {

namespace {

std::string gib(size_t bytes) {
  return strprintf("%.2f GiB", static_cast<double>(bytes) / (1024.0 * 1024.0 * 1024.0));
}

// A cgroup limit file's value: "max" (no limit) and unreadable files are 0.
uint64_t read_limit(const char* path) {
  std::ifstream in(path);
  std::string s;
  if (!(in >> s) || s == "max") return 0;
  char* end = nullptr;
  const unsigned long long v = std::strtoull(s.c_str(), &end, 10);
  return end && *end == '\0' ? v : 0;
}

}  // namespace

size_t result_floats_per_texel(const EncodingPlan& plan) {
  size_t f = kIrradianceFloats + 2 * kScalarImageFloats;
  for (size_t k = 0; k < plan.encodings.size(); ++k) f += coefficient_floats(plan, k);
  return f;
}

size_t largest_image_floats(const EncodingPlan& plan) {
  size_t f = kIrradianceFloats;
  for (size_t k = 0; k < plan.encodings.size(); ++k) f = std::max(f, coefficient_floats(plan, k));
  return f;
}

size_t state_bytes_per_slot(const EncodingPlan& plan, const BakeSettings& settings) {
  // BakeCheckpoint's per-slot arrays (shards/checkpoint.h), with the
  // radiance cache's mean and guiding's histograms where they may be on.
  return sizeof(cl::float4) * 2 + sizeof(cl::float2) + sizeof(uint32_t) + plan.bytes_per_texel() +
         (settings.radiance_cache ? sizeof(cl::float4) : 0) +
         (settings.guiding ? kGuideStride * sizeof(cl::float4) : 0);
}

size_t HostMemoryEstimate::total() const {
  // The bake phase (state read back beside the device buffers), the
  // denoiser and output assembly run one after the other beside the result
  // images; the finished tiles are kept until the result is returned.
  const size_t bake = device_bytes + tile_state;
  return result_bytes + sample_info + scene_bytes + finished_state +
         std::max({bake, denoise_bytes + device_bytes, output_bytes});
}

std::string HostMemoryEstimate::describe() const {
  std::vector<std::pair<size_t, const char*>> parts = {
      {result_bytes, "result images"},
      {device_bytes, "device buffers (CPU device: host memory)"},
      {tile_state, "a tile's state read back"},
      {finished_state, "finished tiles' state"},
      {denoise_bytes, "denoiser"},
      {output_bytes, "output assembly"},
      {sample_info, "sample info"},
      {scene_bytes, "scene"}};
  std::stable_sort(parts.begin(), parts.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  std::string s;
  for (const auto& [bytes, what] : parts) {
    if (bytes == 0) continue;
    if (!s.empty()) s += ", ";
    s += strprintf("%s %s", what, gib(bytes).c_str());
  }
  return s;
}

Result<HostMemoryEstimate> estimate_host_memory(const ResourceEstimate& e,
                                                const BakeSettings& settings, bool device_is_host,
                                                bool checkpoints) {
  auto plan = plan_encodings(settings.encodings);
  if (!plan) return plan.status();
  const EncodingPlan& p = plan.value();
  HostMemoryEstimate h;
  h.texels = e.min_texels;
  h.covered = e.min_covered > 0 ? std::min(e.min_covered, e.min_texels) : e.min_texels;
  const size_t t = static_cast<size_t>(h.texels), c = static_cast<size_t>(h.covered);
  h.result_bytes = t * result_floats_per_texel(p) * sizeof(float);
  // The host's own copies of the scene's device buffers (triangle soup,
  // BVH, textures) and Embree's BVH beside them.
  h.scene_bytes = 2 * e.scene_bytes;
  // offsets per texel; per covered texel its valid mask and one record at least.
  h.sample_info = t * sizeof(uint32_t) + c * 6 * sizeof(uint32_t);
  // The device part: the whole bake's buffers, or the budget it is tiled to.
  const size_t device = std::min(e.device_bytes(c), std::max(e.budget, e.device_bytes(0)));
  if (device_is_host) h.device_bytes = device;
  // A tile holds what fits the budget beside the fixed buffers.
  const size_t per_slot = std::max<size_t>(1, e.per_texel_bytes);
  const size_t room = e.budget > e.device_bytes(0) ? e.budget - e.device_bytes(0) : 0;
  const size_t tile_slots = std::min(c, std::max<size_t>(1, room / per_slot));
  // Checkpoints and snapshots (a daemon's bakes) read a whole tile; a bake
  // without them or the denoiser's variances reads it in slices.
  const bool whole_tile = checkpoints || settings.sharded() || settings.denoise != Denoise::kOff;
  h.tile_state = (whole_tile ? tile_slots : std::min(tile_slots, kStateSliceSlots)) *
                 state_bytes_per_slot(p, settings);
  // Shards keep every tile's state for their accumulators; tiled bakes that
  // checkpoint keep the finished tiles' and assemble each checkpoint of the
  // whole atlas in the same arrays (baker_tiles.cpp, tiled_checkpoint).
  const bool tiled = tile_slots < c;
  if (settings.sharded() || (tiled && checkpoints))
    h.finished_state = c * state_bytes_per_slot(p, settings);
  if (settings.denoise != Denoise::kOff) {
    // Guides (position, normal, chart), the filter's buffers, the variances
    // (Welford, two-point, the kept one) and the denoised map.
    h.denoise_bytes = t * (Denoiser::kBytesPerTexel + 16 + 16 + 4 + 3 * sizeof(float) +
                           kIrradianceFloats * sizeof(float));
    // OIDN's directional mode keeps a denoised copy of each SH encoding.
    for (size_t k = 0; k < p.encodings.size(); ++k)
      if (p.encodings[k].basis.describe().name.rfind("sh", 0) == 0)
        h.result_bytes += t * coefficient_floats(p, k) * sizeof(float);
  }
  // One page image at a time (post/bake_outputs.cpp, the job's
  // write_bake_outputs_releasing): a one-page result's image is moved out
  // of the result, a page of several is a copy of its rows; beside it the
  // page's coverage, dilation's state byte and ring of texel indices, the
  // relative errors seam stitching reads. The EXR is encoded straight
  // into its file.
  const bool pages = e.max_texels > e.min_texels;
  h.output_bytes = t * ((pages ? largest_image_floats(p) * sizeof(float) : 0) + sizeof(float) + 1 +
                        sizeof(size_t) + sizeof(float));
  return h;
}

Status check_host_memory(const HostMemoryEstimate& h, const BakeSettings& settings, size_t budget,
                         const std::string& budget_name) {
  if (budget == 0 || h.total() <= budget) return Status::ok();
  const auto& as = settings.atlas;
  std::string size = as.resolution > 0
                         ? strprintf("settings.resolution %d (%llu texels)", as.resolution,
                                     static_cast<unsigned long long>(h.texels))
                         : strprintf("settings.texel_density %g (at least %llu texels)",
                                     as.texel_density, static_cast<unsigned long long>(h.texels));
  std::string encodings;
  for (const std::string& n : settings.encodings.names)
    encodings += (encodings.empty() ? "" : ",") + n;
  return resource_exhausted(strprintf(
      "host memory: %s with settings.encodings '%s' and settings.denoise '%s' needs an estimated "
      "%zu bytes (%s: %s) of host memory, more than the host-memory budget of %zu bytes (%s, "
      "%s); lower the resolution or the encodings, or raise the budget",
      size.c_str(), encodings.empty() ? "irradiance" : encodings.c_str(),
      choice_name(settings.denoise), h.total(), gib(h.total()).c_str(), h.describe().c_str(),
      budget, gib(budget).c_str(), budget_name.c_str()));
}

uint64_t host_memory_bytes() {
  uint64_t total = 0;
  {
    std::ifstream in("/proc/meminfo");
    std::string key;
    uint64_t kib = 0;
    std::string unit;
    while (in >> key >> kib >> unit)
      if (key == "MemTotal:") {
        total = kib * 1024;
        break;
      }
  }
  if (total == 0) {
    const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
    if (pages > 0 && page > 0) total = static_cast<uint64_t>(pages) * static_cast<uint64_t>(page);
  }
  for (const char* path :
       {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"}) {
    const uint64_t limit = read_limit(path);
    // cgroup v1 reports "no limit" as a huge number.
    if (limit > 0 && (total == 0 || limit < total)) total = limit;
  }
  return total;
}

size_t default_host_memory_budget() {
  return static_cast<size_t>(host_memory_bytes() / 2);
}

}  // namespace luxel::pipeline
