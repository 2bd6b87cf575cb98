// The ray queries of the wavefront bake behind one interface, with two
// backends over the same ray, index and result buffers (RadeonRays shipped
// the same split):
//   OpenCL  kernels/intersect.cl traversal on the bake's device (ClTracer):
//           GPUs, and CPUs when asked;
//   Embree  Embree's stream queries on the host, straight on the mapped
//           device buffers (EmbreeIntersector): CPU devices, where the
//           OpenCL buffers are host memory.
// Both run the same alpha test (kernels/shared/alpha_mask.h) and take the
// rays the bake kernels built with the shared robust offset, so a bake
// traces the same geometry through either; each backend is deterministic on
// its own (its bits differ from the other's in the last place).
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "accel/bvh_builder.h"
#include "common/choices.h"
#include "common/status.h"
#include "device/context.h"
#include "device/feature_set.h"

namespace luxel::accel {

// The settings' intersector choice (choice_name: "auto", "embree", "opencl").
#define LUXEL_INTERSECTOR_CHOICES(X) X(kAuto, "auto") X(kEmbree, "embree") X(kOpenCl, "opencl")
LUXEL_CHOICE_ENUM(IntersectorKind, LUXEL_INTERSECTOR_CHOICES)

class Intersector {
 public:
  virtual ~Intersector() = default;
  virtual IntersectorKind kind() const = 0;
  // What the backend compiled or chose (reported with the bake's features).
  virtual const device::FeatureSet& features() const = 0;
  virtual size_t device_bytes() const = 0;

  // Entry i < *ray_count of `indices` traces rays[indices[i] & index_mask]
  // and writes the result at that source index (thesis §5.1, §5.4). The live
  // count stays on the device; `capacity` bounds the list.
  virtual Status closest_indexed(const device::Buffer& rays, const device::Buffer& indices,
                                 const device::Buffer& ray_count, uint32_t index_mask,
                                 const device::Buffer& hits, size_t capacity) = 0;
  virtual Status any_indexed(const device::Buffer& rays, const device::Buffer& indices,
                             const device::Buffer& ray_count, uint32_t index_mask,
                             const device::Buffer& occluded, size_t capacity) = 0;

  // The live count the last query read on the host (at most its capacity),
  // for backends that read it there anyway (Embree, before it traces); none
  // when it stayed on the device. The stage after a query can then launch
  // over the live paths instead of the list's capacity: the work-items past
  // the count only return, which cost 1-2 % of a PoCL bake.
  virtual std::optional<size_t> host_count() const { return std::nullopt; }
};

// kAuto: Embree on CPU devices, OpenCL on the others. `bvh` must outlive the
// intersector (the Embree backend reads its triangles in place).
Result<std::unique_ptr<Intersector>> make_intersector(IntersectorKind kind, device::Context& ctx,
                                                      const DeviceBvh& bvh);

}  // namespace luxel::accel
