// What a bake holds in host memory, known at submit: the result images
// (irradiance, samples, relative error and every encoding's coefficients,
// full lightmap size from the start: begin_result), the sample-info buffer,
// the accumulation state read back per tile, the finished tiles kept for
// checkpoints and shards, the denoiser's guides and buffers, and the
// transient copies of output assembly (post/bake_outputs.cpp). On a CPU
// device (PoCL) device buffers are host memory too, so the device part
// (resource_estimate.h) counts here as well.
//
// The bake sizes its host buffers with the functions below (begin_result,
// read_state, the denoiser), so the estimate and the bake agree on the
// per-texel figures; what the estimate cannot know before the layout (the
// covered texels at a fixed resolution) it takes at its most (every texel
// covered), so the figure is an upper bound of the bake's own buffers.
// The process itself (libraries, the OpenCL runtime's compiled kernels,
// the imported scene) is not counted.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "bake/encodings.h"
#include "bake/resource_estimate.h"
#include "common/status.h"
#include "settings/bake_settings.h"

namespace luxel::pipeline {

// Floats per texel of BakeResult's images: irradiance RGBA, samples and
// relative error (begin_result sizes them with these).
inline constexpr size_t kIrradianceFloats = 4;
inline constexpr size_t kScalarImageFloats = 1;
// Floats per texel of encoding k's coefficients (count x RGB).
inline size_t coefficient_floats(const EncodingPlan& plan, size_t k) {
  return static_cast<size_t>(plan.table[k].count) * 3;
}
// All of BakeResult's per-texel floats, encodings included.
size_t result_floats_per_texel(const EncodingPlan& plan);
// The largest one image of output assembly (floats per texel): the
// irradiance RGBA or one encoding's coefficients.
size_t largest_image_floats(const EncodingPlan& plan);

// Covered slots a finished tile is read back at a time when nothing needs
// all of its state at once (bake.cpp, finish_tile: no checkpoints of a
// tiled bake, no progressive variance for the denoiser).
inline constexpr size_t kStateSliceSlots = size_t{1} << 20;

// Host bytes per covered slot of a state read back from the device
// (BakeCheckpoint: mean, M2, weight, samples, the encodings' state).
size_t state_bytes_per_slot(const EncodingPlan& plan);

struct HostMemoryEstimate {
  uint64_t texels = 0;        // of the lightmap (all pages)
  uint64_t covered = 0;       // taken at most: every texel, unless known
  size_t result_bytes = 0;    // BakeResult's images for the whole bake
  size_t sample_info = 0;     // offsets per texel, words per covered texel (at least 6)
  size_t scene_bytes = 0;     // host copies of the scene's buffers, Embree's BVH
  size_t tile_state = 0;      // one tile's state read back (reports, checkpoints, finish)
  size_t finished_state = 0;  // finished tiles kept (checkpoints of a tiled bake, shards)
  size_t denoise_bytes = 0;   // guides, variances, the denoised map and the filter's buffers
  size_t output_bytes = 0;    // output assembly: one page image, its coverage, dilation
  size_t device_bytes = 0;    // device memory counted on the host (CPU devices), else 0
  size_t total() const;
  // "result images 9.0 GiB, device (CPU) 4.0 GiB, ..." largest first.
  std::string describe() const;
};

// The estimate for `e` (estimate_bake_resources) under `settings`;
// device_is_host: a CPU device, whose buffers are host memory (the device
// part is then the bake's device estimate, at most its budget);
// checkpoints: the host writes checkpoints (the daemon unless
// --checkpoint-interval 0), so a tiled bake keeps its finished tiles and
// assembles whole-atlas checkpoints in their arrays.
Result<HostMemoryEstimate> estimate_host_memory(const ResourceEstimate& e,
                                                const BakeSettings& settings, bool device_is_host,
                                                bool checkpoints);

// RESOURCE_EXHAUSTED naming the settings that size it (settings.resolution
// or texel_density, settings.encodings, settings.denoise, the device) and
// the bytes against `budget` (0: not checked). `budget_name` says where the
// budget comes from (the daemon's flag, the CLI's).
Status check_host_memory(const HostMemoryEstimate& h, const BakeSettings& settings, size_t budget,
                         const std::string& budget_name);

// The machine's memory as this process may use it: the smaller of
// /proc/meminfo's MemTotal and the cgroup's limit (/sys/fs/cgroup/memory.max,
// cgroup v2; memory.limit_in_bytes, v1). 0 when neither can be read.
uint64_t host_memory_bytes();
// The default host-memory budget: half of host_memory_bytes().
size_t default_host_memory_budget();

}  // namespace luxel::pipeline
