// Embree CPU tracer over the same world-space triangles and rays as the
// OpenCL kernels: Luxel's CPU backend and the test oracle.
//
// It is built from a DeviceBvh's triangle array (leaf order), so Embree's
// primID is the index into that array and hits report the same original
// triangle id (LuxTriangle.v0.w) as the OpenCL kernels. Alpha-masked
// triangles go through an Embree filter callback that runs the very same
// alpha test as the kernels (kernels/shared/alpha_mask.h). The scene is
// built with RTC_SCENE_FLAG_ROBUST (watertight traversal).
#pragma once

#include <embree3/rtcore.h>

#include <memory>
#include <span>

#include "accel/bvh_builder.h"
#include "accel/chunk_pool.h"
#include "common/status.h"
#include "kernels/shared/geometry.h"

namespace luxel::accel {

class EmbreeTracer {
 public:
  static Result<std::unique_ptr<EmbreeTracer>> create(const DeviceBvh& bvh);
  ~EmbreeTracer();
  EmbreeTracer(const EmbreeTracer&) = delete;
  EmbreeTracer& operator=(const EmbreeTracer&) = delete;

  // Closest hits for every ray, on `threads` threads (0: all cores).
  // `coherent` hints Embree that neighbouring rays are coherent.
  void intersect(std::span<const cl::LuxRay> rays, std::span<cl::LuxHit> hits,
                 bool coherent = false, unsigned threads = 0) const;
  // Any hit: occluded[i] = 1 when something blocks ray i in [tmin, tmax].
  void occluded(std::span<const cl::LuxRay> rays, std::span<int> occluded, bool coherent = false,
                unsigned threads = 0) const;

  // Indexed forms, as the wavefront bake's OpenCL kernels do them (thesis
  // §5.1, §5.4): entry i < count traces rays[indices[i] & index_mask] and
  // writes its result at that source index. A ray with an empty interval
  // (tmax <= tmin, "no shadow ray") is not occluded.
  void intersect_indexed(const cl::LuxRay* rays, const uint32_t* indices, size_t count,
                         uint32_t index_mask, cl::LuxHit* hits, unsigned threads = 0) const;
  void occluded_indexed(const cl::LuxRay* rays, const uint32_t* indices, size_t count,
                        uint32_t index_mask, int* occluded, unsigned threads = 0) const;

  double build_ms() const { return build_ms_; }

 private:
  EmbreeTracer() = default;
  cl::LuxHit to_hit(const RTCRayHit& rh) const;
  RTCScene scene_ = nullptr;
  const DeviceBvh* bvh_ = nullptr;  // triangles, uvs and masks for ids and the alpha filter
  double build_ms_ = 0.0;
  ChunkPool pool_{0};  // the queries' threads, one per core
};

}  // namespace luxel::accel
