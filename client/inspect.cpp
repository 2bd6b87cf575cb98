// `luxel inspect SCENE`: what Luxel sees in a scene and how fast it traces it.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "accel/bvh_builder.h"
#include "accel/cl_tracer.h"
#include "accel/embree_tracer.h"
#include "accel/ray_gen.h"
#include "accel/throughput.h"
#include "accel/triangle_soup.h"
#include "bake/lightmap_layout.h"
#include "commands.h"
#include "device/context.h"
#include "scene/gltf_import.h"
#include "scene/scene_stats.h"
#include "settings/settings_schema.h"

namespace luxel::cli {
namespace {

struct InspectArgs {
  std::string scene;
  std::string device;
  size_t rays = 1u << 20;
  uint64_t seed = 1;
  bool trace = true;
  // --uv: the lightmap UVs a bake would generate (--uv generate), laid out
  // at --resolution or --texel-density, and their quality report.
  bool uv = false;
  pipeline::BakeSettings uv_settings;
};

bool parse(const std::vector<std::string>& args, InspectArgs& out) {
  // The size a bake gets without size options (settings schema).
  out.uv_settings.atlas = pipeline::default_settings().atlas;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto value = [&](const char* name) -> const std::string* {
      if (i + 1 >= args.size()) {
        std::fprintf(stderr, "luxel inspect: %s needs a value\n", name);
        return nullptr;
      }
      return &args[++i];
    };
    if (a == "--device") {
      const auto* v = value("--device");
      if (!v) return false;
      out.device = *v;
    } else if (a == "--rays") {
      const auto* v = value("--rays");
      if (!v) return false;
      char* end = nullptr;
      const long long n = std::strtoll(v->c_str(), &end, 10);
      if (*end != '\0' || n < 1 || n > (1ll << 26)) {
        std::fprintf(stderr,
                     "luxel inspect: --rays must be an integer in [1, 67108864], got '%s'\n",
                     v->c_str());
        return false;
      }
      out.rays = static_cast<size_t>(n);
    } else if (a == "--seed") {
      const auto* v = value("--seed");
      if (!v) return false;
      out.seed = std::strtoull(v->c_str(), nullptr, 10);
    } else if (a == "--no-trace") {
      out.trace = false;
    } else if (a == "--uv") {
      out.uv = true;
    } else if (a == "--resolution" || a == "--texel-density" || a == "--max-resolution") {
      const auto* v = value(a.c_str());
      if (!v) return false;
      char* end = nullptr;
      const double d = std::strtod(v->c_str(), &end);
      atlas::AtlasSettings& as = out.uv_settings.atlas;
      const bool integer = a != "--texel-density";
      if (*end != '\0' || !(d > 0 && d <= 65536) || (integer && d != std::floor(d))) {
        std::fprintf(stderr, "luxel inspect: %s must be %s in (0, 65536], got '%s'\n", a.c_str(),
                     integer ? "an integer" : "a number", v->c_str());
        return false;
      }
      if (a == "--resolution") as.resolution = static_cast<int>(d);
      if (a == "--resolution") as.texel_density = 0;
      if (a == "--max-resolution") as.max_resolution = static_cast<int>(d);
      if (a == "--texel-density") {
        as.texel_density = static_cast<float>(d);
        as.resolution = 0;
      }
    } else if (!a.empty() && a[0] == '-') {
      std::fprintf(stderr, "luxel inspect: unknown option '%s'\n", a.c_str());
      return false;
    } else if (out.scene.empty()) {
      out.scene = a;
    } else {
      std::fprintf(stderr, "luxel inspect: unexpected argument '%s'\n", a.c_str());
      return false;
    }
  }
  if (out.scene.empty()) {
    std::fprintf(stderr,
                 "usage: luxel inspect SCENE.gltf|SCENE.glb [--device SPEC] [--rays N] [--seed S] "
                 "[--no-trace]\n"
                 "       [--uv [--resolution N | --texel-density D] [--max-resolution N]]\n");
    return false;
  }
  return true;
}

int fail(const Status& st) {
  std::fprintf(stderr, "luxel: %s\n", st.to_string().c_str());
  return 1;
}

// The quality report of generated lightmap UVs (uv::UvReport; the manifest's
// uv_layout carries the same figures).
int report_uvs(const scene::Scene& scene, pipeline::BakeSettings settings,
               const std::string& file) {
  // What the default --uv auto does; when it keeps the file's TEXCOORD_1,
  // the layout --uv generate would make instead.
  settings.uv = pipeline::UvMode::kAuto;
  auto layout = pipeline::lay_out_lightmap(scene, settings);
  std::string auto_does;
  if (layout && layout->generated) {
    auto_does = "--uv auto generates them: " + layout->generated->reason;
  } else {
    auto_does = layout ? "--uv auto bakes the file's TEXCOORD_1; these are what --uv generate makes"
                       : "--uv auto refuses: " + layout.status().message();
    settings.uv = pipeline::UvMode::kGenerate;
    layout = pipeline::lay_out_lightmap(scene, settings);
  }
  if (!layout)
    return fail(
        Status(layout.status().code(), "scene '" + file + "': " + layout.status().message()));
  const atlas::Atlas& at = layout->atlas;
  const uv::UvReport& u = layout->generated->report;
  std::printf("\nlightmap UVs, generated (%s)\n", auto_does.c_str());
  std::printf("atlas      %d x %d%s at %.4g texels per unit\n", at.width, at.page_height(),
              at.pages > 1 ? strprintf(", %d pages", at.pages).c_str() : "", at.texels_per_unit);
  for (const auto& w : at.warnings) std::printf("warning    %s\n", w.c_str());
  std::printf(
      "charts     %zu on %zu meshes (%zu triangles, %zu degenerate left out, %zu seam vertices)\n",
      u.charts, u.meshes, u.triangles, u.unplaced_triangles, u.seam_vertices);
  std::printf("stretch    L2 %.4f, Linf %.4f (Sander et al. 2001; 1 = none)\n", u.stretch_l2,
              u.stretch_linf);
  std::printf("packing    %.1f %% of the atlas texels covered (%d packings tried)\n",
              100 * u.efficiency, u.pack_attempts);
  std::printf("density    spread %.3f (largest / smallest texels per unit over instances)\n",
              u.density_spread);
  std::printf("overlaps   %zu texel centres inside two triangles%s\n", u.overlapping_texels,
              u.overlapping_texels ? " (a layout error)" : "");
  std::printf("time       %.2f s (charts %.2f s, packing %.2f s)\n", u.total_seconds,
              u.chart_seconds, u.pack_seconds);
  return u.overlapping_texels == 0 ? 0 : 1;
}

// Which TEXCOORD set holds each primitive's lightmap UVs (TEXCOORD_1, or
// the one extras.lightmapTexCoord names, as Luxel's write-back records it).
std::string describe_lightmap_sets(const scene::Scene& scene) {
  std::map<int, size_t> sets;
  size_t missing = 0;
  for (const scene::Mesh& mesh : scene.meshes)
    for (const scene::Mesh::PrimitiveSpan& span : mesh.primitive_spans)
      span.has_lightmap_uvs ? ++sets[span.lightmap_texcoord] : ++missing;
  std::string out;
  for (const auto& [set, count] : sets)
    out += strprintf("%sTEXCOORD_%d on %zu primitive%s", out.empty() ? "" : ", ", set, count,
                     count == 1 ? "" : "s");
  if (sets.size() > 1 || (sets.size() == 1 && sets.begin()->first != 1))
    out += " (extras.lightmapTexCoord)";
  if (missing > 0)
    out += strprintf("%s%zu primitive%s without lightmap UVs (--uv auto generates them)",
                     out.empty() ? "" : "; ", missing, missing == 1 ? "" : "s");
  return out;
}

}  // namespace

int run_devices(const std::vector<std::string>&) {
  auto devices = device::list_devices();
  if (!devices) return fail(devices.status());
  auto chosen = device::choose_device("");
  for (const auto& d : devices.value())
    std::printf("%s %d:%d  %s\n", chosen && chosen->id == d.id ? "*" : " ", d.platform_index,
                d.device_index, d.describe().c_str());
  return 0;
}

int run_inspect(const std::vector<std::string>& argv) {
  InspectArgs args;
  if (!parse(argv, args)) return 2;

  const auto t0 = std::chrono::steady_clock::now();
  auto scene = scene::import_gltf_file(args.scene);
  if (!scene) return fail(scene.status());
  const double import_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const scene::SceneStats stats = scene::compute_stats(scene.value());
  std::printf("scene      %s (imported in %.0f ms)\n", args.scene.c_str(), import_ms);
  std::printf("%s", scene::format_stats(stats).c_str());
  for (const auto& w : scene->import_stats.warnings) std::printf("warning    %s\n", w.c_str());
  std::printf("lightmap set %s\n", describe_lightmap_sets(scene.value()).c_str());
  if (stats.world_triangles == 0) {
    // Nothing to bake (no meshes, or only points and lines); tracing an empty
    // scene would measure nothing either.
    std::fprintf(stderr, "luxel inspect: '%s' has no triangles to bake\n", args.scene.c_str());
    return 1;
  }
  if (args.uv) {
    const int uv_status = report_uvs(scene.value(), args.uv_settings, args.scene);
    if (uv_status != 0) return uv_status;
  }

  auto ctx = device::Context::create(args.device);
  if (!ctx) return fail(ctx.status());
  std::printf("device     %s\n", ctx.value()->info().describe().c_str());
  // What `luxel bake --intersector auto` uses on this device.
  std::printf("intersector %s for bakes (auto on a %s; --intersector embree|opencl to choose)\n",
              ctx.value()->info().is_gpu ? "opencl" : "embree",
              ctx.value()->info().is_gpu ? "GPU" : "CPU device");

  auto soup = accel::build_triangle_soup(scene.value());
  if (!soup) return fail(soup.status());
  accel::BvhBuildOptions bvh_options;
  bvh_options.width = accel::preferred_bvh_width(ctx.value()->info());
  auto bvh = accel::build_bvh(soup.value(), bvh_options);
  if (!bvh) return fail(bvh.status());
  const auto& bs = bvh->stats;
  std::printf(
      "bvh        BVH%u, %zu nodes, %zu leaves, depth %u, SAH cost %.1f, built in %.1f ms (Embree "
      "rtcBuildBVH), %.1f MiB on device\n",
      bvh->width, bs.nodes, bs.leaves, bs.max_depth, bs.sah_cost, bs.build_ms,
      static_cast<double>(bs.device_bytes) / (1024.0 * 1024.0));

  const auto tc = std::chrono::steady_clock::now();
  auto cl_tracer = accel::ClTracer::create(*ctx.value(), bvh.value());
  if (!cl_tracer) return fail(cl_tracer.status());
  std::printf(
      "kernels    intersect.cl, features: %s (ready in %.0f ms)\n",
      cl_tracer.value()->features().describe().c_str(),
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tc).count());
  auto embree = accel::EmbreeTracer::create(bvh.value());
  if (!embree) return fail(embree.status());
  if (!args.trace) return 0;

  std::printf(
      "\nray throughput, %zu rays per set (best of 3; OpenCL: kernel time, Embree: wall time on "
      "all cores)\n",
      args.rays);
  std::printf("%-12s %-8s %14s %14s %12s\n", "rays", "query", "OpenCL Mray/s", "Embree Mray/s",
              "CL/Embree");
  const accel::RayKind kinds[] = {accel::RayKind::kCoherent, accel::RayKind::kIncoherent,
                                  accel::RayKind::kShadow};
  for (const auto kind : kinds) {
    const auto rays = accel::make_rays(soup.value(), kind, args.rays, args.seed);
    const auto query =
        kind == accel::RayKind::kShadow ? accel::Query::kAny : accel::Query::kClosest;
    auto tp = accel::measure_throughput(*ctx.value(), *cl_tracer.value(), *embree.value(), rays,
                                        query, kind == accel::RayKind::kCoherent);
    if (!tp) return fail(tp.status());
    std::printf("%-12s %-8s %14.2f %14.2f %11.2fx\n", accel::ray_kind_name(kind),
                query == accel::Query::kAny ? "any" : "closest", tp->cl_mrays(), tp->embree_mrays(),
                tp->ratio());
  }
  std::printf("\nkernel launches (OpenCL profiling events, all passes)\n%s",
              ctx.value()->timer().table().c_str());
  return 0;
}

}  // namespace luxel::cli
