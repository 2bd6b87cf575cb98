#include "accel/embree_tracer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include "accel/embree_device.h"
#include "kernels/shared/alpha_mask.h"

namespace luxel::accel {
namespace {

// Rays per rtcIntersect1M call and per work chunk handed to a thread.
constexpr size_t kStream = 64;
constexpr size_t kChunk = 4096;

// Embree filter: reject a candidate hit where the alpha mask is transparent.
void alpha_filter(const RTCFilterFunctionNArguments* args) {
  const auto* bvh = static_cast<const DeviceBvh*>(args->geometryUserPtr);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    const unsigned prim = RTCHitN_primID(args->hit, args->N, i);
    const int mask = cl::as_int(bvh->triangles[prim].v1.w);
    if (mask < 0) continue;
    const float u = RTCHitN_u(args->hit, args->N, i);
    const float v = RTCHitN_v(args->hit, args->N, i);
    if (!cl::lux_alpha_opaque(&bvh->uvs[prim], &bvh->masks[static_cast<size_t>(mask)],
                              bvh->alpha_texels.data(), u, v))
      args->valid[i] = 0;
  }
}

void to_embree(const cl::LuxRay& r, RTCRay& e) {
  e.org_x = r.org_tmin.x;
  e.org_y = r.org_tmin.y;
  e.org_z = r.org_tmin.z;
  e.tnear = r.org_tmin.w;
  e.dir_x = r.dir_tmax.x;
  e.dir_y = r.dir_tmax.y;
  e.dir_z = r.dir_tmax.z;
  e.tfar = r.dir_tmax.w;
  e.time = 0.0f;
  e.mask = 0xFFFFFFFFu;
  e.id = 0;
  e.flags = 0;
}

void init_hit(RTCRayHit& rh) {
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

RTCIntersectContext make_context(bool coherent) {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags =
      coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
  return ctx;
}

}  // namespace

Result<std::unique_ptr<EmbreeTracer>> EmbreeTracer::create(const DeviceBvh& bvh) {
  auto device = embree_device();
  if (!device) return device.status();
  const auto t0 = std::chrono::steady_clock::now();
  std::unique_ptr<EmbreeTracer> tracer(new EmbreeTracer());
  tracer->bvh_ = &bvh;
  RTCDevice dev = device.value();
  tracer->scene_ = rtcNewScene(dev);
  rtcSetSceneFlags(tracer->scene_, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(tracer->scene_, RTC_BUILD_QUALITY_HIGH);

  const size_t n = bvh.stats.triangles;
  if (n > 0) {
    RTCGeometry geom = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    // Vertices are read straight out of the LuxTriangle records (stride 16:
    // each float4 holds one vertex; .w carries ids Embree ignores).
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                               bvh.triangles.data(), 0, sizeof(cl::float4), n * 3);
    auto* index = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), n));
    if (!index) {
      rtcReleaseGeometry(geom);
      return resource_exhausted(strprintf("Embree index buffer for %zu triangles", n));
    }
    for (size_t i = 0; i < n * 3; ++i) index[i] = static_cast<unsigned>(i);
    if (bvh.has_alpha_masks()) {
      rtcSetGeometryUserData(geom, const_cast<DeviceBvh*>(&bvh));
      rtcSetGeometryIntersectFilterFunction(geom, alpha_filter);
      rtcSetGeometryOccludedFilterFunction(geom, alpha_filter);
    }
    rtcCommitGeometry(geom);
    rtcAttachGeometry(tracer->scene_, geom);
    rtcReleaseGeometry(geom);
  }
  rtcCommitScene(tracer->scene_);
  if (const RTCError err = rtcGetDeviceError(dev); err != RTC_ERROR_NONE)
    return internal_error(strprintf("Embree scene build failed (error %d)", static_cast<int>(err)));
  tracer->build_ms_ =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return tracer;
}

EmbreeTracer::~EmbreeTracer() {
  if (scene_) rtcReleaseScene(scene_);
}

void EmbreeTracer::intersect(std::span<const cl::LuxRay> rays, std::span<cl::LuxHit> hits,
                             bool coherent, unsigned threads) const {
  pool_.run(rays.size(), kChunk, threads, [&](size_t begin, size_t end) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags =
        coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    RTCRayHit batch[kStream];
    for (size_t s = begin; s < end; s += kStream) {
      const size_t m = std::min(kStream, end - s);
      for (size_t i = 0; i < m; ++i) {
        to_embree(rays[s + i], batch[i].ray);
        batch[i].hit.geomID = RTC_INVALID_GEOMETRY_ID;
        batch[i].hit.primID = RTC_INVALID_GEOMETRY_ID;
        batch[i].hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      }
      rtcIntersect1M(scene_, &ctx, batch, static_cast<unsigned>(m), sizeof(RTCRayHit));
      for (size_t i = 0; i < m; ++i) {
        cl::LuxHit& h = hits[s + i];
        if (batch[i].hit.geomID == RTC_INVALID_GEOMETRY_ID) {
          h = {batch[i].ray.tfar, 0.0f, 0.0f, -1};
        } else {
          h = {batch[i].ray.tfar, batch[i].hit.u, batch[i].hit.v,
               cl::as_int(bvh_->triangles[batch[i].hit.primID].v0.w)};
        }
      }
    }
  });
}

void EmbreeTracer::occluded(std::span<const cl::LuxRay> rays, std::span<int> occluded,
                            bool coherent, unsigned threads) const {
  pool_.run(rays.size(), kChunk, threads, [&](size_t begin, size_t end) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags =
        coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    RTCRay batch[kStream];
    for (size_t s = begin; s < end; s += kStream) {
      const size_t m = std::min(kStream, end - s);
      for (size_t i = 0; i < m; ++i) to_embree(rays[s + i], batch[i]);
      rtcOccluded1M(scene_, &ctx, batch, static_cast<unsigned>(m), sizeof(RTCRay));
      // Embree marks an occluded ray by setting tfar to -inf.
      for (size_t i = 0; i < m; ++i) occluded[s + i] = batch[i].tfar < 0.0f ? 1 : 0;
    }
  });
}

cl::LuxHit EmbreeTracer::to_hit(const RTCRayHit& rh) const {
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return {rh.ray.tfar, 0.0f, 0.0f, -1};
  return {rh.ray.tfar, rh.hit.u, rh.hit.v, cl::as_int(bvh_->triangles[rh.hit.primID].v0.w)};
}

void EmbreeTracer::intersect_indexed(const cl::LuxRay* rays, const uint32_t* indices, size_t count,
                                     uint32_t index_mask, cl::LuxHit* hits,
                                     unsigned threads) const {
  pool_.run(count, kChunk, threads, [&](size_t begin, size_t end) {
    RTCIntersectContext ctx = make_context(false);
    RTCRayHit batch[kStream];
    uint32_t slot[kStream];
    for (size_t s = begin; s < end; s += kStream) {
      const size_t m = std::min(kStream, end - s);
      for (size_t i = 0; i < m; ++i) {
        slot[i] = indices[s + i] & index_mask;
        to_embree(rays[slot[i]], batch[i].ray);
        init_hit(batch[i]);
      }
      rtcIntersect1M(scene_, &ctx, batch, static_cast<unsigned>(m), sizeof(RTCRayHit));
      for (size_t i = 0; i < m; ++i) hits[slot[i]] = to_hit(batch[i]);
    }
  });
}

void EmbreeTracer::occluded_indexed(const cl::LuxRay* rays, const uint32_t* indices, size_t count,
                                    uint32_t index_mask, int* occluded, unsigned threads) const {
  pool_.run(count, kChunk, threads, [&](size_t begin, size_t end) {
    RTCIntersectContext ctx = make_context(false);
    RTCRay batch[kStream];
    uint32_t slot[kStream];
    for (size_t s = begin; s < end; s += kStream) {
      const size_t m = std::min(kStream, end - s);
      for (size_t i = 0; i < m; ++i) {
        slot[i] = indices[s + i] & index_mask;
        to_embree(rays[slot[i]], batch[i]);
      }
      rtcOccluded1M(scene_, &ctx, batch, static_cast<unsigned>(m), sizeof(RTCRay));
      // Embree marks an occluded ray by setting tfar to -inf; an empty
      // interval is inactive and stays unoccluded (as intersect_any_indexed).
      for (size_t i = 0; i < m; ++i) {
        const cl::LuxRay& r = rays[slot[i]];
        occluded[slot[i]] = r.dir_tmax.w > r.org_tmin.w && batch[i].tfar == -INFINITY ? 1 : 0;
      }
    }
  });
}

}  // namespace luxel::accel
