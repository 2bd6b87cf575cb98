#include "accel/bvh_builder.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <mutex>

#include "accel/embree_device.h"

namespace luxel::accel {
namespace {

// Transient tree produced by Embree's callbacks; memory comes from Embree's
// thread-local allocator and is freed with the RTCBVH.
struct BuildNode {
  bool leaf;
};
constexpr unsigned kMaxWidth = 4;
struct BuildInner : BuildNode {
  BuildNode* child[kMaxWidth];
  RTCBounds bounds[kMaxWidth];
  unsigned count;
};
struct BuildLeaf : BuildNode {
  unsigned count;
  unsigned prims[1];  // `count` entries (allocated with the leaf)
};

bool build_progress(void* cancel, double) {
  return !static_cast<const CancelToken*>(cancel)->requested();
}

void* create_node(RTCThreadLocalAllocator alloc, unsigned num_children, void*) {
  auto* n = static_cast<BuildInner*>(rtcThreadLocalAlloc(alloc, sizeof(BuildInner), 16));
  n->leaf = false;
  n->count = std::min(num_children, kMaxWidth);
  for (unsigned i = 0; i < kMaxWidth; ++i) n->child[i] = nullptr;
  return n;
}

void set_children(void* node, void** children, unsigned n, void*) {
  auto* inner = static_cast<BuildInner*>(node);
  for (unsigned i = 0; i < n && i < kMaxWidth; ++i)
    inner->child[i] = static_cast<BuildNode*>(children[i]);
}

void set_bounds(void* node, const RTCBounds** bounds, unsigned n, void*) {
  auto* inner = static_cast<BuildInner*>(node);
  for (unsigned i = 0; i < n && i < kMaxWidth; ++i) inner->bounds[i] = *bounds[i];
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

double area_of_node(const BuildInner* node) {
  RTCBounds u = node->bounds[0];
  for (unsigned i = 1; i < node->count; ++i) {
    const RTCBounds& b = node->bounds[i];
    u.lower_x = std::min(u.lower_x, b.lower_x);
    u.lower_y = std::min(u.lower_y, b.lower_y);
    u.lower_z = std::min(u.lower_z, b.lower_z);
    u.upper_x = std::max(u.upper_x, b.upper_x);
    u.upper_y = std::max(u.upper_y, b.upper_y);
    u.upper_z = std::max(u.upper_z, b.upper_z);
  }
  return area(u);
}

// Lane i of a host float4 / int4 (the host structs have no subscript).
float& lane(cl::float4& v, int i) {
  return i == 0 ? v.x : i == 1 ? v.y : i == 2 ? v.z : v.w;
}
int32_t& lane(cl::int4& v, int i) {
  return i == 0 ? v.x : i == 1 ? v.y : i == 2 ? v.z : v.w;
}

// A BVH4 node whose four slots are all absent (kernels/shared/geometry.h).
cl::LuxBvh4Node empty_node4() {
  const cl::float4 inf{INFINITY, INFINITY, INFINITY, INFINITY};
  return {inf, inf, inf, inf, inf, inf, {-1, -1, -1, -1}, {0, 0, 0, 0}};
}

// Appends the leaf's triangles in leaf order; shared by both layouts.
class LeafWriter {
 public:
  LeafWriter(const TriangleSoup& soup, const BvhBuildOptions& opt, DeviceBvh& out)
      : soup_(soup), opt_(opt), out_(out) {}

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

 protected:
  const TriangleSoup& soup_;
  const BvhBuildOptions& opt_;
  DeviceBvh& out_;
};

// Fat BVH2 nodes (LuxBvhNode).
class Flattener : public LeafWriter {
 public:
  Flattener(const TriangleSoup& soup, const BvhBuildOptions& opt, DeviceBvh& out)
      : LeafWriter(soup, opt, out) {}

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

 private:
  static void set_child(cl::float4& lo, cl::float4& hi, const RTCBounds* b, int ref, int count) {
    if (!b) {  // absent child: inverted bounds, no ray enters
      lo = pack(INFINITY, INFINITY, INFINITY, -1);
      hi = pack(-INFINITY, -INFINITY, -INFINITY, 0);
      return;
    }
    lo = pack(b->lower_x, b->lower_y, b->lower_z, ref);
    hi = pack(b->upper_x, b->upper_y, b->upper_z, count);
  }
};

// BVH4 nodes (LuxBvh4Node): up to four slots, SoA bounds.
class Flattener4 : public LeafWriter {
 public:
  Flattener4(const TriangleSoup& soup, const BvhBuildOptions& opt, DeviceBvh& out)
      : LeafWriter(soup, opt, out) {}

  int inner(const BuildInner* binary_or_wide, unsigned depth) {
    out_.stats.max_depth = std::max(out_.stats.max_depth, depth);
    const int index = static_cast<int>(out_.nodes4.size());
    out_.nodes4.push_back(empty_node4());
    BuildInner collapsed;
    const BuildInner* node = binary_or_wide;
    if (opt_.collapse) {
      collapsed = collapse(*binary_or_wide);
      node = &collapsed;
    }
    out_.stats.sah_cost += opt_.traversal_cost * area_of_node(node);
    int ref[kMaxWidth], count[kMaxWidth];
    for (unsigned c = 0; c < kMaxWidth; ++c) {
      ref[c] = -1;
      count[c] = 0;
      const BuildNode* child = c < node->count ? node->child[c] : nullptr;
      if (!child) continue;
      if (child->leaf)
        leaf(static_cast<const BuildLeaf*>(child), node->bounds[c], depth + 1, ref[c], count[c]);
      else
        ref[c] = inner(static_cast<const BuildInner*>(child), depth + 1);
    }
    // The recursion may have reallocated nodes4: index only now.
    cl::LuxBvh4Node& n = out_.nodes4[static_cast<size_t>(index)];
    for (unsigned c = 0; c < kMaxWidth; ++c) {
      if (ref[c] < 0) continue;  // absent: stays +INFINITY, -1
      const int i = static_cast<int>(c);
      const RTCBounds& b = node->bounds[c];
      lane(n.lo_x, i) = b.lower_x;
      lane(n.hi_x, i) = b.upper_x;
      lane(n.lo_y, i) = b.lower_y;
      lane(n.hi_y, i) = b.upper_y;
      lane(n.lo_z, i) = b.lower_z;
      lane(n.hi_z, i) = b.upper_z;
      lane(n.child, i) = ref[c];
      lane(n.count, i) = count[c];
    }
    return index;
  }

 private:
  // Pulls grandchildren up into `node` until it has four children: always
  // the inner child of largest surface area is replaced by its children (the
  // greedy SAH collapse of a binary tree, Wald, Benthin and Boulos 2008
  // "Getting Rid of Packets" §3; Embree's wide builder does the same while
  // building).
  static BuildInner collapse(const BuildInner& node) {
    BuildInner wide = node;
    for (;;) {
      int best = -1;
      double best_area = -1.0;
      for (unsigned c = 0; c < wide.count; ++c) {
        const BuildNode* child = wide.child[c];
        if (!child || child->leaf) continue;
        const auto* in = static_cast<const BuildInner*>(child);
        if (wide.count - 1 + in->count > kMaxWidth) continue;
        const double a = area(wide.bounds[c]);
        if (a > best_area) {
          best_area = a;
          best = static_cast<int>(c);
        }
      }
      if (best < 0) return wide;
      const BuildInner open = *static_cast<const BuildInner*>(wide.child[best]);
      wide.child[best] = open.child[0];
      wide.bounds[best] = open.bounds[0];
      for (unsigned c = 1; c < open.count; ++c) {
        wide.child[wide.count] = open.child[c];
        wide.bounds[wide.count] = open.bounds[c];
        ++wide.count;
      }
    }
  }
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
  if (options.width != 2 && options.width != 4)
    return invalid_argument(strprintf("BVH width %u (2 or 4)", options.width));
  auto device = embree_device();
  if (!device) return device.status();
  const auto t0 = std::chrono::steady_clock::now();

  DeviceBvh out;
  out.width = options.width;
  out.masks = soup.masks;
  out.alpha_texels = soup.alpha_texels;
  const size_t n = soup.size();
  if (n == 0) {
    if (options.width == 4) {
      out.nodes4.push_back(empty_node4());
    } else {
      cl::LuxBvhNode root{};
      const cl::float4 lo{INFINITY, INFINITY, INFINITY, cl::as_float(-1)};
      const cl::float4 hi{-INFINITY, -INFINITY, -INFINITY, cl::as_float(0)};
      root.lmin = root.rmin = lo;
      root.lmax = root.rmax = hi;
      out.nodes.push_back(root);
    }
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
  // Width 4: Embree's wide builder fills each node by repeatedly splitting
  // the child of largest surface area with a binned SAH split, i.e. the
  // top-down collapse of the binary SAH tree into a 4-ary one (Wald, Benthin
  // and Boulos 2008, "Getting Rid of Packets", §3).
  args.maxBranchingFactor = options.collapse ? 2 : options.width;
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
  // The monitor returns false to abort (Embree then returns no root and
  // RTC_ERROR_CANCELLED); userPtr reaches it and the node callbacks, which
  // ignore it.
  args.buildProgress = options.cancel.flag() ? build_progress : nullptr;
  args.userPtr = const_cast<CancelToken*>(&options.cancel);

  auto* root = static_cast<BuildNode*>(rtcBuildBVH(&args));
  if (!root && options.cancel.requested()) {
    rtcReleaseBVH(bvh);
    return cancelled_error("the BVH build");
  }
  if (!root) {
    const RTCError err = rtcGetDeviceError(device.value());
    rtcReleaseBVH(bvh);
    return internal_error(strprintf("rtcBuildBVH failed over %zu triangles (Embree error %d)", n,
                                    static_cast<int>(err)));
  }

  // A single leaf is wrapped in a root whose other children are absent.
  BuildInner wrapper{};
  if (root->leaf) {
    wrapper.leaf = false;
    wrapper.count = 1;
    wrapper.child[0] = root;
    Bounds3 all = soup.bounds;
    wrapper.bounds[0] = {all.lo.x, all.lo.y, all.lo.z, 0, all.hi.x, all.hi.y, all.hi.z, 0};
  }
  const BuildInner* top = root->leaf ? &wrapper : static_cast<const BuildInner*>(root);
  out.triangles.reserve(n);
  if (options.width == 4) {
    out.nodes4.reserve(n / 2);
    Flattener4(soup, options, out).inner(top, 0);
  } else {
    out.nodes.reserve(n);
    Flattener(soup, options, out).inner(top, 0);
  }
  rtcReleaseBVH(bvh);

  // Normalize the SAH cost by the root's surface area.
  const Vec3 e = soup.bounds.extent();
  const double root_area = 2.0 * (double(e.x) * e.y + double(e.y) * e.z + double(e.z) * e.x);
  out.stats.sah_cost = root_area > 0 ? out.stats.sah_cost / root_area : 0.0;
  out.stats.nodes = out.width == 4 ? out.nodes4.size() : out.nodes.size();
  out.stats.triangles = out.triangles.size();
  out.stats.device_bytes =
      out.nodes.size() * sizeof(cl::LuxBvhNode) + out.nodes4.size() * sizeof(cl::LuxBvh4Node) +
      out.triangles.size() * sizeof(cl::LuxTriangle) + out.uvs.size() * sizeof(cl::LuxTriangleUV) +
      out.masks.size() * sizeof(cl::LuxAlphaMask) + out.alpha_texels.size();
  out.stats.build_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

unsigned required_stack_size(const DeviceBvh& bvh) {
  // BVH2 pushes at most one child per level, BVH4 at most three.
  return (bvh.width == 4 ? 3 : 1) * bvh.stats.max_depth + 1;
}

unsigned preferred_bvh_width(const device::DeviceInfo& device) {
  if (const char* env = std::getenv("LUXEL_BVH_WIDTH")) {
    if (std::strcmp(env, "2") == 0) return 2;
    if (std::strcmp(env, "4") == 0) return 4;
  }
  return device.is_gpu ? 2 : 4;
}

}  // namespace luxel::accel
