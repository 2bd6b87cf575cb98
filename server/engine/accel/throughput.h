// Ray throughput of the OpenCL kernels and of Embree on the same rays, in one
// run (used by `luxel inspect` and tests/bench/rays).
#pragma once

#include <vector>

#include "accel/cl_tracer.h"
#include "accel/embree_tracer.h"
#include "common/status.h"
#include "device/context.h"

namespace luxel::accel {

struct Throughput {
  size_t rays = 0;
  double cl_ms = 0.0;      // best kernel time over the repeats (profiling events)
  double embree_ms = 0.0;  // best wall time over the repeats, all cores
  double cl_mrays() const { return cl_ms > 0 ? rays / (cl_ms * 1e3) : 0.0; }
  double embree_mrays() const { return embree_ms > 0 ? rays / (embree_ms * 1e3) : 0.0; }
  double ratio() const {
    return embree_ms > 0 && cl_ms > 0 ? embree_ms / cl_ms : 0.0;
  }  // CL / Embree throughput
};

enum class Query { kClosest, kAny };

// Runs one warm-up and `repeats` timed passes of each tracer over `rays`.
Result<Throughput> measure_throughput(device::Context& ctx, ClTracer& cl_tracer,
                                      const EmbreeTracer& embree,
                                      const std::vector<cl::LuxRay>& rays, Query query,
                                      bool coherent, int repeats = 3);

}  // namespace luxel::accel
