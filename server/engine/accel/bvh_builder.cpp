#include "accel/bvh_builder.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>

#include "accel/embree_device.h"

namespace luxel::accel {
namespace {

// Transient tree produced by Embree's callbacks; memory comes from Embree's
// thread-local allocator and is freed with the RTCBVH.
struct BuildNode {
  bool leaf;
};
struct BuildInner : BuildNode {
  BuildNode* child[2];
  RTCBounds bounds[2];
  unsigned count;
};
struct BuildLeaf : BuildNode {
  unsigned count;
  unsigned prims[1];  // `count` entries (allocated with the leaf)
};

void* create_node(RTCThreadLocalAllocator alloc, unsigned num_children, void*) {
  auto* n = static_cast<BuildInner*>(rtcThreadLocalAlloc(alloc, sizeof(BuildInner), 16));
  n->leaf = false;
  n->count = num_children;
  n->child[0] = n->child[1] = nullptr;
  return n;
}

void set_children(void* node, void** children, unsigned n, void*) {
  auto* inner = static_cast<BuildInner*>(node);
  for (unsigned i = 0; i < n && i < 2; ++i) inner->child[i] = static_cast<BuildNode*>(children[i]);
}

void set_bounds(void* node, const RTCBounds** bounds, unsigned n, void*) {
  auto* inner = static_cast<BuildInner*>(node);
  for (unsigned i = 0; i < n && i < 2; ++i) inner->bounds[i] = *bounds[i];
}

void* create_leaf(RTCThreadLocalAllocator alloc, const RTCBuildPrimitive* prims, size_t n, void*) {
  const size_t bytes = sizeof(BuildLeaf) + sizeof(unsigned) * (n > 0 ? n - 1 : 0);
  auto* leaf = static_cast<BuildLeaf*>(rtcThreadLocalAlloc(alloc, bytes, 16));
  leaf->leaf = true;
  leaf->count = static_cast<unsigned>(n);
  for (size_t i = 0; i < n; ++i) leaf->prims[i] = prims[i].primID;
  return leaf;
}

double area(const RTCBounds& b) {
  const double dx = std::max(0.0f, b.upper_x - b.lower_x);
  const double dy = std::max(0.0f, b.upper_y - b.lower_y);
  const double dz = std::max(0.0f, b.upper_z - b.lower_z);
  return 2.0 * (dx * dy + dy * dz + dz * dx);
}

cl::float4 pack(float x, float y, float z, int w) {
  return {x, y, z, cl::as_float(w)};
}

class Flattener {
 public:
  Flattener(const TriangleSoup& soup, const BvhBuildOptions& opt, DeviceBvh& out)
      : soup_(soup), opt_(opt), out_(out) {}

  // Appends `node` (an inner node) and its subtree; returns its index.
  int inner(const BuildInner* node, unsigned depth) {
    out_.stats.max_depth = std::max(out_.stats.max_depth, depth);
    const int index = static_cast<int>(out_.nodes.size());
    out_.nodes.emplace_back();
    out_.stats.sah_cost += opt_.traversal_cost * area_of_node(node);
    int ref[2] = {0, 0}, count[2] = {0, 0};
    for (int c = 0; c < 2; ++c) {
      const BuildNode* child = c < static_cast<int>(node->count) ? node->child[c] : nullptr;
      if (!child) continue;
      if (child->leaf)
        leaf(static_cast<const BuildLeaf*>(child), node->bounds[c], depth + 1, ref[c], count[c]);
      else
        ref[c] = inner(static_cast<const BuildInner*>(child), depth + 1);
    }
    cl::LuxBvhNode& n = out_.nodes[static_cast<size_t>(index)];
    set_child(n.lmin, n.lmax, node->count > 0 ? &node->bounds[0] : nullptr, ref[0], count[0]);
    set_child(n.rmin, n.rmax, node->count > 1 ? &node->bounds[1] : nullptr, ref[1], count[1]);
    return index;
  }

  void leaf(const BuildLeaf* leaf, const RTCBounds& bounds, unsigned depth, int& first,
            int& count) {
    out_.stats.max_depth = std::max(out_.stats.max_depth, depth);
    out_.stats.leaves += 1;
    out_.stats.sah_cost += opt_.intersection_cost * leaf->count * area(bounds);
    first = static_cast<int>(out_.triangles.size());
    count = static_cast<int>(leaf->count);
    for (unsigned i = 0; i < leaf->count; ++i) {
      const unsigned t = leaf->prims[i];
      const Vec3 a = soup_.v(t, 0), b = soup_.v(t, 1), c = soup_.v(t, 2);
      out_.triangles.push_back({pack(a.x, a.y, a.z, static_cast<int>(t)),
                                pack(b.x, b.y, b.z, soup_.alpha_mask[t]), pack(c.x, c.y, c.z, 0)});
      if (soup_.has_alpha_masks()) out_.uvs.push_back(soup_.uvs[t]);
    }
  }

 private:
  static double area_of_node(const BuildInner* node) {
    RTCBounds u = node->bounds[0];
    if (node->count > 1) {
      const RTCBounds& b = node->bounds[1];
      u.lower_x = std::min(u.lower_x, b.lower_x);
      u.lower_y = std::min(u.lower_y, b.lower_y);
      u.lower_z = std::min(u.lower_z, b.lower_z);
      u.upper_x = std::max(u.upper_x, b.upper_x);
      u.upper_y = std::max(u.upper_y, b.upper_y);
      u.upper_z = std::max(u.upper_z, b.upper_z);
    }
    return area(u);
  }

  static void set_child(cl::float4& lo, cl::float4& hi, const RTCBounds* b, int ref, int count) {
    if (!b) {  // absent child: inverted bounds, no ray enters
      lo = pack(INFINITY, INFINITY, INFINITY, -1);
      hi = pack(-INFINITY, -INFINITY, -INFINITY, 0);
      return;
    }
    lo = pack(b->lower_x, b->lower_y, b->lower_z, ref);
    hi = pack(b->upper_x, b->upper_y, b->upper_z, count);
  }

  const TriangleSoup& soup_;
  const BvhBuildOptions& opt_;
  DeviceBvh& out_;
};

}  // namespace

Result<RTCDevice> embree_device() {
  static std::once_flag once;
  static RTCDevice device = nullptr;
  std::call_once(once, [] { device = rtcNewDevice("threads=0"); });
  if (!device)
    return unavailable(
        strprintf("Embree device creation failed (error %d)", rtcGetDeviceError(nullptr)));
  return device;
}

Result<DeviceBvh> build_bvh(const TriangleSoup& soup, const BvhBuildOptions& options) {
  auto device = embree_device();
  if (!device) return device.status();
  const auto t0 = std::chrono::steady_clock::now();

  DeviceBvh out;
  out.masks = soup.masks;
  out.alpha_texels = soup.alpha_texels;
  const size_t n = soup.size();
  if (n == 0) {
    cl::LuxBvhNode root{};
    const cl::float4 lo{INFINITY, INFINITY, INFINITY, cl::as_float(-1)};
    const cl::float4 hi{-INFINITY, -INFINITY, -INFINITY, cl::as_float(0)};
    root.lmin = root.rmin = lo;
    root.lmax = root.rmax = hi;
    out.nodes.push_back(root);
    out.triangles.push_back({});  // keep buffers non-empty
    out.stats.nodes = 1;
    return out;
  }

  // The SAH builder may add primitives when splitting; reserve headroom as
  // Embree's documentation asks for primitiveArrayCapacity.
  std::vector<RTCBuildPrimitive> prims(n);
  prims.reserve(n * 2);
  for (size_t t = 0; t < n; ++t) {
    Bounds3 b;
    for (int k = 0; k < 3; ++k) b.extend(soup.v(t, k));
    prims[t] = {b.lo.x, b.lo.y, b.lo.z, 0u, b.hi.x, b.hi.y, b.hi.z, static_cast<unsigned>(t)};
  }

  RTCBVH bvh = rtcNewBVH(device.value());
  RTCBuildArguments args = rtcDefaultBuildArguments();
  args.byteSize = sizeof(args);
  args.buildFlags = RTC_BUILD_FLAG_NONE;
  args.buildQuality = RTC_BUILD_QUALITY_MEDIUM;  // binned SAH
  args.maxBranchingFactor = 2;
  args.maxDepth = options.max_depth;
  args.sahBlockSize = 1;
  args.minLeafSize = 1;
  args.maxLeafSize = options.max_leaf_size;
  args.traversalCost = options.traversal_cost;
  args.intersectionCost = options.intersection_cost;
  args.bvh = bvh;
  args.primitives = prims.data();
  args.primitiveCount = n;
  args.primitiveArrayCapacity = prims.capacity();
  args.createNode = create_node;
  args.setNodeChildren = set_children;
  args.setNodeBounds = set_bounds;
  args.createLeaf = create_leaf;
  args.splitPrimitive = nullptr;
  args.buildProgress = nullptr;
  args.userPtr = nullptr;

  auto* root = static_cast<BuildNode*>(rtcBuildBVH(&args));
  if (!root) {
    const RTCError err = rtcGetDeviceError(device.value());
    rtcReleaseBVH(bvh);
    return internal_error(strprintf("rtcBuildBVH failed over %zu triangles (Embree error %d)", n,
                                    static_cast<int>(err)));
  }

  out.nodes.reserve(n);
  out.triangles.reserve(n);
  Flattener flat(soup, options, out);
  if (root->leaf) {
    // A single leaf: wrap it in a root whose right child is absent.
    BuildInner wrapper{};
    wrapper.leaf = false;
    wrapper.count = 1;
    wrapper.child[0] = root;
    Bounds3 all = soup.bounds;
    wrapper.bounds[0] = {all.lo.x, all.lo.y, all.lo.z, 0, all.hi.x, all.hi.y, all.hi.z, 0};
    flat.inner(&wrapper, 0);
  } else {
    flat.inner(static_cast<BuildInner*>(root), 0);
  }
  rtcReleaseBVH(bvh);

  // Normalize the SAH cost by the root's surface area.
  const Vec3 e = soup.bounds.extent();
  const double root_area = 2.0 * (double(e.x) * e.y + double(e.y) * e.z + double(e.z) * e.x);
  out.stats.sah_cost = root_area > 0 ? out.stats.sah_cost / root_area : 0.0;
  out.stats.nodes = out.nodes.size();
  out.stats.triangles = out.triangles.size();
  out.stats.device_bytes = out.nodes.size() * sizeof(cl::LuxBvhNode) +
                           out.triangles.size() * sizeof(cl::LuxTriangle) +
                           out.uvs.size() * sizeof(cl::LuxTriangleUV) +
                           out.masks.size() * sizeof(cl::LuxAlphaMask) + out.alpha_texels.size();
  out.stats.build_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

unsigned required_stack_size(const DeviceBvh& bvh) {
  return bvh.stats.max_depth + 1;
}

}  // namespace luxel::accel
