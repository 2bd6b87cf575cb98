#include "accel/embree_intersector.h"

#include <chrono>

#include "accel/cl_tracer.h"
#include "device/cl_error.h"

namespace luxel::accel {

namespace {

// A buffer mapped for the duration of one query; unmapped on scope exit.
class Mapped {
 public:
  Mapped(device::Context& ctx, const device::Buffer& b, cl_map_flags flags, size_t bytes)
      : ctx_(ctx), b_(b) {
    cl_int err = CL_SUCCESS;
    ptr_ = clEnqueueMapBuffer(ctx.queue(), b.get(), CL_TRUE, flags, 0, bytes, 0, nullptr, nullptr,
                              &err);
    status_ = device::cl_status(err, "map buffer for the Embree intersector");
  }
  ~Mapped() {
    if (ptr_) clEnqueueUnmapMemObject(ctx_.queue(), b_.get(), ptr_, 0, nullptr, nullptr);
  }
  Mapped(const Mapped&) = delete;
  Mapped& operator=(const Mapped&) = delete;
  const Status& status() const { return status_; }
  template <typename T>
  T* as() const {
    return static_cast<T*>(ptr_);
  }

 private:
  device::Context& ctx_;
  const device::Buffer& b_;
  void* ptr_ = nullptr;
  Status status_;
};

}  // namespace

Result<std::unique_ptr<EmbreeIntersector>> EmbreeIntersector::create(device::Context& ctx,
                                                                     const DeviceBvh& bvh) {
  auto tracer = EmbreeTracer::create(bvh);
  if (!tracer) return tracer.status();
  std::unique_ptr<EmbreeIntersector> out(new EmbreeIntersector(ctx));
  out->tracer_ = std::move(tracer.value());
  out->features_.set(device::Feature::INTERSECTOR_EMBREE);
  return out;
}

template <typename Result, typename Query>
Status EmbreeIntersector::run(const char* name, const device::Buffer& rays,
                              const device::Buffer& indices, const device::Buffer& ray_count,
                              const device::Buffer& out, size_t capacity, Query&& query) {
  int count = 0;
  {
    // Blocking: waits for the kernels that produced the list and the rays
    // (their time is theirs in the table; the clock starts after).
    Mapped n(ctx_, ray_count, CL_MAP_READ, sizeof(int));
    LUXEL_RETURN_IF_ERROR(n.status());
    count = *n.as<int>();
  }
  host_count_ = std::min(static_cast<size_t>(std::max(count, 0)), capacity);
  const auto t0 = std::chrono::steady_clock::now();
  if (count > 0) {
    const size_t live = std::min(static_cast<size_t>(count), capacity);
    Mapped list(ctx_, indices, CL_MAP_READ, live * sizeof(uint32_t));
    Mapped r(ctx_, rays, CL_MAP_READ, rays.bytes());
    Mapped o(ctx_, out, CL_MAP_READ | CL_MAP_WRITE, out.bytes());
    for (const Mapped* m : {&list, &r, &o}) LUXEL_RETURN_IF_ERROR(m->status());
    query(r.as<const cl::LuxRay>(), list.as<const uint32_t>(), live, o.as<Result>());
  }
  ctx_.timer().record_host(
      name,
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  return Status::ok();
}

Status EmbreeIntersector::closest_indexed(const device::Buffer& rays, const device::Buffer& indices,
                                          const device::Buffer& ray_count, uint32_t index_mask,
                                          const device::Buffer& hits, size_t capacity) {
  return run<cl::LuxHit>("embree_closest", rays, indices, ray_count, hits, capacity,
                         [&](const cl::LuxRay* r, const uint32_t* list, size_t n, cl::LuxHit* out) {
                           tracer_->intersect_indexed(r, list, n, index_mask, out);
                         });
}

Status EmbreeIntersector::any_indexed(const device::Buffer& rays, const device::Buffer& indices,
                                      const device::Buffer& ray_count, uint32_t index_mask,
                                      const device::Buffer& occluded, size_t capacity) {
  return run<int>("embree_any", rays, indices, ray_count, occluded, capacity,
                  [&](const cl::LuxRay* r, const uint32_t* list, size_t n, int* out) {
                    tracer_->occluded_indexed(r, list, n, index_mask, out);
                  });
}

Result<std::unique_ptr<Intersector>> make_intersector(IntersectorKind kind, device::Context& ctx,
                                                      const DeviceBvh& bvh) {
  if (kind == IntersectorKind::kAuto)
    kind = ctx.info().is_gpu ? IntersectorKind::kOpenCl : IntersectorKind::kEmbree;
  if (kind == IntersectorKind::kEmbree) {
    auto e = EmbreeIntersector::create(ctx, bvh);
    if (!e) return e.status();
    return std::unique_ptr<Intersector>(std::move(e.value()));
  }
  auto c = ClTracer::create(ctx, bvh);
  if (!c) return c.status();
  return std::unique_ptr<Intersector>(std::move(c.value()));
}

}  // namespace luxel::accel
