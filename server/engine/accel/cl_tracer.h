// OpenCL ray queries: the BVH uploaded to the device and the intersection
// program compiled for this scene's features.
#pragma once

#include <memory>
#include <vector>

#include "accel/bvh_builder.h"
#include "accel/intersector.h"
#include "common/status.h"
#include "device/context.h"
#include "device/feature_set.h"
#include "device/program_cache.h"

namespace luxel::accel {

class ClTracer final : public Intersector {
 public:
  // Uploads the BVH (and alpha data only when the scene has masked
  // triangles) and builds kernels/intersect.cl with the matching features:
  // BVH4 when `bvh` has width 4 (see preferred_bvh_width), ALPHA_MASK,
  // STACK_SIZE.
  static Result<std::unique_ptr<ClTracer>> create(device::Context& ctx, const DeviceBvh& bvh);

  // Features the intersection program was compiled with.
  const device::FeatureSet& features() const override { return features_; }
  size_t device_bytes() const override { return device_bytes_; }
  IntersectorKind kind() const override { return IntersectorKind::kOpenCl; }

  // Enqueue on device buffers; `capacity` rays are launched, the kernel reads
  // the live count from `ray_count` (one int). No host synchronisation.
  Status enqueue_closest(const device::Buffer& rays, const device::Buffer& ray_count,
                         const device::Buffer& hits, size_t capacity);
  Status enqueue_any(const device::Buffer& rays, const device::Buffer& ray_count,
                     const device::Buffer& occluded, size_t capacity);

  // Indexed variants (wavefront bake, thesis §5.1/§5.4): work-item i traces
  // rays[indices[i] & index_mask] and writes the result at that source index.
  // ray_count holds the number of valid entries in `indices`.
  Status enqueue_closest_indexed(const device::Buffer& rays, const device::Buffer& indices,
                                 const device::Buffer& ray_count, uint32_t index_mask,
                                 const device::Buffer& hits, size_t capacity);
  Status enqueue_any_indexed(const device::Buffer& rays, const device::Buffer& indices,
                             const device::Buffer& ray_count, uint32_t index_mask,
                             const device::Buffer& occluded, size_t capacity);

  // Intersector: the indexed kernels above.
  Status closest_indexed(const device::Buffer& rays, const device::Buffer& indices,
                         const device::Buffer& ray_count, uint32_t index_mask,
                         const device::Buffer& hits, size_t capacity) override {
    return enqueue_closest_indexed(rays, indices, ray_count, index_mask, hits, capacity);
  }
  Status any_indexed(const device::Buffer& rays, const device::Buffer& indices,
                     const device::Buffer& ray_count, uint32_t index_mask,
                     const device::Buffer& occluded, size_t capacity) override {
    return enqueue_any_indexed(rays, indices, ray_count, index_mask, occluded, capacity);
  }

  // Host-vector conveniences for tests and benchmarks (upload, trace, read back).
  Result<std::vector<cl::LuxHit>> closest(const std::vector<cl::LuxRay>& rays);
  Result<std::vector<int>> any(const std::vector<cl::LuxRay>& rays);

  size_t work_group_size() const { return local_size_; }
  void set_work_group_size(size_t n) { local_size_ = n; }

 private:
  ClTracer(device::Context& ctx) : ctx_(ctx) {}
  template <typename... Args>
  Status launch_with_scene(device::Kernel& kernel, size_t capacity, const Args&... args);
  Status bind_and_launch(device::Kernel& kernel, const device::Buffer& rays,
                         const device::Buffer& ray_count, const device::Buffer& out,
                         size_t capacity);

  device::Context& ctx_;
  device::FeatureSet features_;
  device::Buffer nodes_, triangles_, uvs_, masks_, alpha_texels_;
  device::Kernel closest_, any_, closest_indexed_, any_indexed_;
  size_t device_bytes_ = 0;
  size_t local_size_ = 64;
};

}  // namespace luxel::accel
