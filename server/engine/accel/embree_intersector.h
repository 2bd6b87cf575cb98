// The Embree backend of accel::Intersector for CPU OpenCL devices: each query
// maps the bake's ray, index, count and result buffers (host memory on a CPU
// device, so mapping copies nothing), runs Embree's stream queries on all
// cores and unmaps. The in-order queue orders the maps after the kernels
// that wrote the rays. Every query is timed and named like a kernel
// ("embree_closest", "embree_any") in the bake's timing table.
#pragma once

#include "accel/embree_tracer.h"
#include "accel/intersector.h"

namespace luxel::accel {

class EmbreeIntersector final : public Intersector {
 public:
  static Result<std::unique_ptr<EmbreeIntersector>> create(device::Context& ctx,
                                                           const DeviceBvh& bvh);

  IntersectorKind kind() const override { return IntersectorKind::kEmbree; }
  const device::FeatureSet& features() const override { return features_; }
  size_t device_bytes() const override { return 0; }

  Status closest_indexed(const device::Buffer& rays, const device::Buffer& indices,
                         const device::Buffer& ray_count, uint32_t index_mask,
                         const device::Buffer& hits, size_t capacity) override;
  Status any_indexed(const device::Buffer& rays, const device::Buffer& indices,
                     const device::Buffer& ray_count, uint32_t index_mask,
                     const device::Buffer& occluded, size_t capacity) override;
  std::optional<size_t> host_count() const override { return host_count_; }

 private:
  EmbreeIntersector(device::Context& ctx) : ctx_(ctx) {}
  template <typename Result, typename Query>
  Status run(const char* name, const device::Buffer& rays, const device::Buffer& indices,
             const device::Buffer& ray_count, const device::Buffer& out, size_t capacity,
             Query&& query);

  device::Context& ctx_;
  std::unique_ptr<EmbreeTracer> tracer_;
  device::FeatureSet features_;
  std::optional<size_t> host_count_;
};

}  // namespace luxel::accel
