#include "accel/throughput.h"

#include <algorithm>
#include <chrono>

namespace luxel::accel {

Result<Throughput> measure_throughput(device::Context& ctx, ClTracer& cl_tracer,
                                      const EmbreeTracer& embree,
                                      const std::vector<cl::LuxRay>& rays, Query query,
                                      bool coherent, int repeats) {
  Throughput out;
  out.rays = rays.size();
  if (rays.empty()) return out;
  repeats = std::max(1, repeats);

  auto ray_buf = ctx.upload(rays, "rays");
  if (!ray_buf) return ray_buf.status();
  const int count = static_cast<int>(rays.size());
  auto count_buf = ctx.upload_bytes(&count, sizeof count, "ray count");
  if (!count_buf) return count_buf.status();
  const size_t out_bytes =
      rays.size() * (query == Query::kClosest ? sizeof(cl::LuxHit) : sizeof(int));
  auto out_buf = ctx.alloc(out_bytes, "trace results", CL_MEM_WRITE_ONLY);
  if (!out_buf) return out_buf.status();

  const char* kernel = query == Query::kClosest ? "intersect_closest" : "intersect_any";
  double best = 1e300;
  // The context's timer keeps accumulating (callers may print its table);
  // each pass's kernel time is the difference it adds.
  auto kernel_total = [&] {
    auto it = ctx.timer().stats().find(kernel);
    return it == ctx.timer().stats().end() ? 0.0 : it->second.total_ms;
  };
  for (int r = 0; r <= repeats; ++r) {  // pass 0 warms caches and the driver
    const double before = kernel_total();
    if (query == Query::kClosest)
      LUXEL_RETURN_IF_ERROR(cl_tracer.enqueue_closest(ray_buf.value(), count_buf.value(),
                                                      out_buf.value(), rays.size()));
    else
      LUXEL_RETURN_IF_ERROR(
          cl_tracer.enqueue_any(ray_buf.value(), count_buf.value(), out_buf.value(), rays.size()));
    LUXEL_RETURN_IF_ERROR(ctx.finish());
    if (r > 0) best = std::min(best, kernel_total() - before);
  }
  out.cl_ms = best;

  std::vector<cl::LuxHit> hits(query == Query::kClosest ? rays.size() : 0);
  std::vector<int> occluded(query == Query::kAny ? rays.size() : 0);
  best = 1e300;
  for (int r = 0; r <= repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    if (query == Query::kClosest)
      embree.intersect(rays, hits, coherent);
    else
      embree.occluded(rays, occluded, coherent);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (r > 0) best = std::min(best, ms);
  }
  out.embree_ms = best;
  return out;
}

}  // namespace luxel::accel
