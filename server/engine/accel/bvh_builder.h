// BVH construction with Embree's builder API (rtcBuildBVH, binned SAH) into
// Luxel's device layouts: "fat" BVH2 nodes holding both children's bounds,
// or BVH4 nodes with SoA bounds of four children (kernels/shared/geometry.h
// documents both) over world-space triangles reordered so every leaf is a
// contiguous range.
#pragma once

#include <vector>

#include "accel/triangle_soup.h"
#include "common/cancel.h"
#include "common/status.h"
#include "device/context.h"
#include "kernels/shared/geometry.h"

namespace luxel::accel {

struct BvhBuildOptions {
  unsigned width = 2;           // 2: LuxBvhNode, 4: LuxBvh4Node (see preferred_bvh_width)
  bool collapse = false;        // width 4: build binary, then collapse (else Embree builds 4-wide)
  unsigned max_leaf_size = 4;   // triangles per leaf (the builder may exceed it at max depth)
  unsigned max_depth = 48;      // the traversal stack (LUX_STACK_SIZE) must be deeper
  float traversal_cost = 1.0f;  // SAH cost of one node visit relative to...
  float intersection_cost = 1.0f;  // ...one triangle test
  // Polled by Embree's build-progress monitor: a set request aborts the
  // build with cancelled_error (common/cancel.h).
  CancelToken cancel;
};

struct BvhStats {
  size_t nodes = 0;
  size_t leaves = 0;
  size_t triangles = 0;  // referenced by leaves (== soup size)
  unsigned max_depth = 0;
  double sah_cost = 0.0;    // expected cost per ray, relative to root area (one unit per node
                            // visit whatever its width)
  double build_ms = 0.0;    // rtcBuildBVH plus flattening
  size_t device_bytes = 0;  // nodes + triangles (+ alpha data)
};

struct DeviceBvh {
  unsigned width = 2;                      // which of the two node vectors is filled
  std::vector<cl::LuxBvhNode> nodes;       // width 2; node 0 is the root
  std::vector<cl::LuxBvh4Node> nodes4;     // width 4; node 0 is the root
  std::vector<cl::LuxTriangle> triangles;  // leaf order
  std::vector<cl::LuxTriangleUV> uvs;      // leaf order; empty unless alpha masks
  std::vector<cl::LuxAlphaMask> masks;
  std::vector<uint8_t> alpha_texels;
  BvhStats stats;

  bool has_alpha_masks() const { return !masks.empty(); }
};

// Builds over every triangle of the soup. An empty soup gives a root whose
// children are both absent (every ray misses).
Result<DeviceBvh> build_bvh(const TriangleSoup& soup, const BvhBuildOptions& options = {});

// The stack depth traversal needs for this BVH (BVH2: max depth + 1; BVH4:
// three entries per level + 1).
unsigned required_stack_size(const DeviceBvh& bvh);

// The node width the OpenCL traversal runs fastest with on this device: 4 on
// CPU devices (PoCL: the four box tests become float4 SIMD, measured in
// docs/performance.md), 2 on GPUs (not measured with BVH4 yet). The
// environment variable LUXEL_BVH_WIDTH=2|4 overrides it.
unsigned preferred_bvh_width(const device::DeviceInfo& device);

}  // namespace luxel::accel
