#include "accel/cl_tracer.h"

namespace luxel::accel {

Result<std::unique_ptr<ClTracer>> ClTracer::create(device::Context& ctx, const DeviceBvh& bvh) {
  std::unique_ptr<ClTracer> t(new ClTracer(ctx));
  // The private traversal stack is sized to this BVH (rounded up so similar
  // scenes share a cached program).
  const unsigned stack = (required_stack_size(bvh) + 7u) / 8u * 8u;
  t->features_.set(device::Feature::STACK_SIZE, static_cast<int>(std::max(stack, 16u)));
  if (bvh.has_alpha_masks()) t->features_.set(device::Feature::ALPHA_MASK);
  if (bvh.width == 4) t->features_.set(device::Feature::BVH4);

  auto nodes =
      bvh.width == 4 ? ctx.upload(bvh.nodes4, "bvh4 nodes") : ctx.upload(bvh.nodes, "bvh nodes");
  if (!nodes) return nodes.status();
  t->nodes_ = std::move(nodes.value());
  auto tris = ctx.upload(bvh.triangles, "bvh triangles");
  if (!tris) return tris.status();
  t->triangles_ = std::move(tris.value());
  t->device_bytes_ = t->nodes_.bytes() + t->triangles_.bytes();
  if (bvh.has_alpha_masks()) {
    auto uvs = ctx.upload(bvh.uvs, "alpha-mask triangle uvs");
    if (!uvs) return uvs.status();
    t->uvs_ = std::move(uvs.value());
    auto masks = ctx.upload(bvh.masks, "alpha masks");
    if (!masks) return masks.status();
    t->masks_ = std::move(masks.value());
    auto texels = ctx.upload(bvh.alpha_texels, "alpha-mask texels");
    if (!texels) return texels.status();
    t->alpha_texels_ = std::move(texels.value());
    t->device_bytes_ += t->uvs_.bytes() + t->masks_.bytes() + t->alpha_texels_.bytes();
  }

  auto program = ctx.programs().get("intersect.cl", t->features_);
  if (!program) return program.status();
  auto closest = program.value()->kernel("intersect_closest");
  if (!closest) return closest.status();
  t->closest_ = std::move(closest.value());
  auto any = program.value()->kernel("intersect_any");
  if (!any) return any.status();
  t->any_ = std::move(any.value());
  auto closest_indexed = program.value()->kernel("intersect_closest_indexed");
  if (!closest_indexed) return closest_indexed.status();
  t->closest_indexed_ = std::move(closest_indexed.value());
  auto any_indexed = program.value()->kernel("intersect_any_indexed");
  if (!any_indexed) return any_indexed.status();
  t->any_indexed_ = std::move(any_indexed.value());
  return t;
}

// The scene buffers lead every intersection kernel's argument list; the alpha
// buffers are arguments only in programs compiled with LUX_ALPHA_MASK.
template <typename... Args>
Status ClTracer::launch_with_scene(device::Kernel& kernel, size_t capacity, const Args&... args) {
  if (features_.has(device::Feature::ALPHA_MASK)) {
    LUXEL_RETURN_IF_ERROR(
        kernel.set_args(nodes_, triangles_, uvs_, masks_, alpha_texels_, args...));
  } else {
    LUXEL_RETURN_IF_ERROR(kernel.set_args(nodes_, triangles_, args...));
  }
  return ctx_.launch(kernel, capacity, local_size_);
}

Status ClTracer::bind_and_launch(device::Kernel& kernel, const device::Buffer& rays,
                                 const device::Buffer& ray_count, const device::Buffer& out,
                                 size_t capacity) {
  return launch_with_scene(kernel, capacity, rays, ray_count, out);
}

Status ClTracer::enqueue_closest_indexed(const device::Buffer& rays, const device::Buffer& indices,
                                         const device::Buffer& ray_count, uint32_t index_mask,
                                         const device::Buffer& hits, size_t capacity) {
  return launch_with_scene(closest_indexed_, capacity, rays, indices, ray_count, index_mask, hits);
}

Status ClTracer::enqueue_any_indexed(const device::Buffer& rays, const device::Buffer& indices,
                                     const device::Buffer& ray_count, uint32_t index_mask,
                                     const device::Buffer& occluded, size_t capacity) {
  return launch_with_scene(any_indexed_, capacity, rays, indices, ray_count, index_mask, occluded);
}

Status ClTracer::enqueue_closest(const device::Buffer& rays, const device::Buffer& ray_count,
                                 const device::Buffer& hits, size_t capacity) {
  return bind_and_launch(closest_, rays, ray_count, hits, capacity);
}

Status ClTracer::enqueue_any(const device::Buffer& rays, const device::Buffer& ray_count,
                             const device::Buffer& occluded, size_t capacity) {
  return bind_and_launch(any_, rays, ray_count, occluded, capacity);
}

namespace {

template <typename Out, typename Enqueue>
Result<std::vector<Out>> trace_host(device::Context& ctx, const std::vector<cl::LuxRay>& rays,
                                    Enqueue&& enqueue) {
  std::vector<Out> out(rays.size());
  if (rays.empty()) return out;
  auto ray_buf = ctx.upload(rays, "rays");
  if (!ray_buf) return ray_buf.status();
  const int count = static_cast<int>(rays.size());
  auto count_buf = ctx.upload_bytes(&count, sizeof count, "ray count");
  if (!count_buf) return count_buf.status();
  auto out_buf = ctx.alloc(out.size() * sizeof(Out), "trace results", CL_MEM_WRITE_ONLY);
  if (!out_buf) return out_buf.status();
  LUXEL_RETURN_IF_ERROR(enqueue(ray_buf.value(), count_buf.value(), out_buf.value(), rays.size()));
  LUXEL_RETURN_IF_ERROR(ctx.read(out_buf.value(), out));
  LUXEL_RETURN_IF_ERROR(ctx.finish());
  return out;
}

}  // namespace

Result<std::vector<cl::LuxHit>> ClTracer::closest(const std::vector<cl::LuxRay>& rays) {
  return trace_host<cl::LuxHit>(
      ctx_, rays, [&](auto& r, auto& c, auto& o, size_t n) { return enqueue_closest(r, c, o, n); });
}

Result<std::vector<int>> ClTracer::any(const std::vector<cl::LuxRay>& rays) {
  return trace_host<int>(
      ctx_, rays, [&](auto& r, auto& c, auto& o, size_t n) { return enqueue_any(r, c, o, n); });
}

}  // namespace luxel::accel
