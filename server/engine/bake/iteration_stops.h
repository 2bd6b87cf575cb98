// How long an iteration of a bake may keep a stop request waiting, and when
// the bake gives up the iteration in flight.
//
// The host enqueues an iteration stage by stage (texel domain, sort,
// offset buffer, raygen, then closest hit / shade / shadow rays per bounce)
// and waits once at its end, so a stop request (cancel, or the checkpoint a
// shutting-down host asks for) used to wait for the whole iteration: 15 s
// and more for paths_per_iteration 2^24 on a CPU device. Two rules bound it:
//
//  1. The batch cap. An iteration traces at most iteration_path_cap()
//     paths: 2^17 per compute unit (at least 2^18, the default batch, so
//     default bakes are unchanged), whatever paths_per_iteration asks for.
//     At the ~0.35 M paths/s a CPU core traces at 4 bounces
//     (docs/performance.md: 0.64-0.73 M paths/s on 2 cores) an iteration
//     then takes about 0.4 s on an idle machine, a stage of it a few tens
//     of milliseconds, and a GPU's compute units are faster still. The cap is a property of the
//     device, never of timing: the same settings, seed and device give the same batches and the
//     same bits (a bake with a larger paths_per_iteration simply runs more, smaller iterations; its
//     buffers are sized for the capped batch, bake/resource_estimate.h).
//  2. Stop points. On CPU devices, and on GPUs for batches of 2^22 paths
//     and more, the host waits for the device after every stage and looks
//     at the stop flags there; on a request the iteration is given up
//     before its accumulation, the only stage that writes per-texel state,
//     so the accumulated state (and a checkpoint of it) is exactly that of
//     the completed iterations. Waiting after every stage costs a few tens
//     of microseconds per stage: nothing on a CPU, where a stage of a
//     capped batch takes tens of milliseconds, but a noticeable share of a
//     small GPU iteration, which the cap already keeps short.
//
// An iteration given up for a checkpoint runs again after it with the same
// first path (the same bits); that re-run is not given up for a checkpoint
// again, so a host that keeps checkpoint_now set cannot stall the bake.
#pragma once

#include <algorithm>
#include <cstdint>

#include "bake/bake.h"

namespace luxel::pipeline {

inline constexpr uint64_t kPathsPerComputeUnit = uint64_t{1} << 17;
inline constexpr uint64_t kMinIterationCap = uint64_t{1} << 18;
inline constexpr uint64_t kGpuInterruptibleBatch = uint64_t{1} << 22;

// The most paths one iteration traces on a device with `compute_units`
// (0: unknown, no cap).
inline uint64_t iteration_path_cap(unsigned compute_units) {
  if (compute_units == 0) return UINT64_MAX;
  return std::max(kMinIterationCap, uint64_t{compute_units} * kPathsPerComputeUnit);
}

// Whether an iteration of `batch` paths checks for stops between stages:
// hosts that can ask for a stop, on CPUs always, on GPUs for large batches.
inline bool iteration_interruptible(const BakeHooks& hooks, uint64_t batch, bool gpu) {
  return (hooks.cancel || hooks.checkpoint_now) && (!gpu || batch >= kGpuInterruptibleBatch);
}

// A stop request: cancel, or (allow_checkpoint) a checkpoint asked for by a
// host that writes them.
inline bool stop_requested(const BakeHooks& hooks, bool allow_checkpoint) {
  if (hooks.cancel && hooks.cancel->load()) return true;
  return allow_checkpoint && hooks.on_checkpoint && hooks.checkpoint_now &&
         hooks.checkpoint_now->load();
}

}  // namespace luxel::pipeline
