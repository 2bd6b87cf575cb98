// tests/bench/rays: ray throughput of the OpenCL kernels (on the default
// OpenCL device, PoCL on a CPU-only machine) and of Embree, on the same rays
// and scenes, in one run. Prints a markdown table for docs/performance.md.
//
//   bench_rays [--rays N] [--repeats R] [--device SPEC] [--work-group W]
//              [--leaf-size L] [--intersection-cost C] [--bvh 2|4|both] [--collapse] SCENE...
//   (no SCENE: every bundled scene and every shared benchmark scene;
//   --bvh: the OpenCL node layout, default both: one row per width;
//   --collapse: BVH4 by collapsing Embree's binary tree instead of its
//   4-wide build)
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "accel/bvh_builder.h"
#include "accel/cl_tracer.h"
#include "accel/embree_tracer.h"
#include "accel/ray_gen.h"
#include "accel/throughput.h"
#include "accel/triangle_soup.h"
#include "common/machine_info.h"
#include "device/context.h"
#include "scene/gltf_import.h"

namespace fs = std::filesystem;
using namespace luxel;

namespace {

std::vector<std::string> default_scenes() {
  std::vector<std::string> out;
  for (const char* dir : {LUXEL_SCENES_DIR, LUXEL_SHARED_SCENES_DIR}) {
    if (!fs::is_directory(dir)) continue;
    std::vector<std::string> here;
    for (const auto& e : fs::directory_iterator(dir)) {
      const auto ext = e.path().extension();
      if (ext == ".gltf" || ext == ".glb") here.push_back(e.path().string());
    }
    std::sort(here.begin(), here.end());
    out.insert(out.end(), here.begin(), here.end());
  }
  return out;
}

int fail(const Status& st) {
  std::fprintf(stderr, "bench_rays: %s\n", st.to_string().c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  size_t rays = 1u << 20;
  int repeats = 3;
  size_t work_group = 0;
  accel::BvhBuildOptions bvh_options;
  std::string device_spec;
  std::vector<std::string> scenes;
  std::vector<unsigned> widths = {2, 4};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--rays" && i + 1 < argc)
      rays = std::strtoull(argv[++i], nullptr, 10);
    else if (a == "--repeats" && i + 1 < argc)
      repeats = std::atoi(argv[++i]);
    else if (a == "--device" && i + 1 < argc)
      device_spec = argv[++i];
    else if (a == "--work-group" && i + 1 < argc)
      work_group = std::strtoull(argv[++i], nullptr, 10);
    else if (a == "--leaf-size" && i + 1 < argc)
      bvh_options.max_leaf_size = static_cast<unsigned>(std::atoi(argv[++i]));
    else if (a == "--intersection-cost" && i + 1 < argc)
      bvh_options.intersection_cost = std::strtof(argv[++i], nullptr);
    else if (a == "--collapse")
      bvh_options.collapse = true;
    else if (a == "--bvh" && i + 1 < argc) {
      const std::string w = argv[++i];
      widths = w == "2"   ? std::vector<unsigned>{2}
               : w == "4" ? std::vector<unsigned>{4}
                          : std::vector<unsigned>{2, 4};
    } else if (!a.empty() && a[0] == '-') {
      std::fprintf(
          stderr,
          "usage: bench_rays [--rays N] [--repeats R] [--device SPEC] [--work-group W] "
          "[--leaf-size L] [--intersection-cost C] [--bvh 2|4|both] [--collapse] [SCENE...]\n");
      return 2;
    } else
      scenes.push_back(a);
  }
  if (scenes.empty()) scenes = default_scenes();

  auto ctx = device::Context::create(device_spec);
  if (!ctx) return fail(ctx.status());
  std::printf("machine: %s\n", describe(machine_info()).c_str());
  std::printf("OpenCL device: %s\n", ctx.value()->info().describe().c_str());
  std::printf(
      "rays per set: %zu, best of %d passes; OpenCL = kernel time from profiling events, "
      "Embree = wall time of rtcIntersect1M/rtcOccluded1M on all hardware threads\n\n",
      rays, repeats);
  std::printf(
      "| scene | triangles | BVH | nodes | SAH | rays | query | OpenCL Mrays/s | Embree Mrays/s | "
      "OpenCL / Embree |\n");
  std::printf("|---|---:|---:|---:|---:|---|---|---:|---:|---:|\n");
  for (const auto& path : scenes) {
    auto scene = scene::import_gltf_file(path);
    if (!scene) return fail(scene.status());
    auto soup = accel::build_triangle_soup(scene.value());
    if (!soup) return fail(soup.status());
    const std::string name = fs::path(path).stem().string();
    for (unsigned width : widths) {
      bvh_options.width = width;
      auto bvh = accel::build_bvh(soup.value(), bvh_options);
      if (!bvh) return fail(bvh.status());
      auto cl = accel::ClTracer::create(*ctx.value(), bvh.value());
      if (!cl) return fail(cl.status());
      if (work_group) cl.value()->set_work_group_size(work_group);
      auto embree = accel::EmbreeTracer::create(bvh.value());
      if (!embree) return fail(embree.status());
      for (auto kind :
           {accel::RayKind::kCoherent, accel::RayKind::kIncoherent, accel::RayKind::kShadow}) {
        const auto set = accel::make_rays(soup.value(), kind, rays, 99);
        const auto query =
            kind == accel::RayKind::kShadow ? accel::Query::kAny : accel::Query::kClosest;
        auto tp = accel::measure_throughput(*ctx.value(), *cl.value(), *embree.value(), set, query,
                                            kind == accel::RayKind::kCoherent, repeats);
        if (!tp) return fail(tp.status());
        std::printf("| %s | %zu | %u | %zu | %.1f | %s | %s | %.2f | %.2f | %.2f |\n", name.c_str(),
                    soup->size(), width, bvh->stats.nodes, bvh->stats.sah_cost,
                    accel::ray_kind_name(kind), query == accel::Query::kAny ? "any" : "closest",
                    tp->cl_mrays(), tp->embree_mrays(), tp->ratio());
        std::fflush(stdout);
      }
    }
  }
  return 0;
}
