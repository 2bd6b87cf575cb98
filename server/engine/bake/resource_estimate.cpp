#include "bake/resource_estimate.h"

#include <algorithm>
#include <cmath>

#include "atlas/chart_geometry.h"
#include "bake/encodings.h"
#include "bake/iteration_stops.h"
#include "bake/tile_plan.h"
#include "kernels/shared/bake.h"
#include "kernels/shared/geometry.h"

namespace luxel::pipeline {

namespace {

double mib(double bytes) {
  return bytes / (1024.0 * 1024.0);
}

// Pages a layout of this scene may use: generated UVs at a density go on up
// to 64 pages (uv::GenerateOptions::max_pages); the file's TEXCOORD_1 on
// one, or on the pages of its placements.
// With a resolution, generated UVs are counted on one page of it: they
// take several only when the charts fit it at no density (uv/generate.h),
// tiny pages whose texels do not bound the batch. Placements (the file's
// lightmapIndex or the client's) use their pages.
int pages_allowed(const scene::Scene& scene, const BakeSettings& s) {
  if (s.atlas.resolution == 0 && s.uv != UvMode::kExisting && s.node_placements.empty()) return 64;
  int pages = 1;
  for (const scene::Instance& inst : scene.instances)
    pages = std::max(pages, inst.lightmap_page + 1);
  for (const NodePlacement& np : s.node_placements) pages = std::max(pages, np.page + 1);
  return pages;
}

size_t scene_bytes(const scene::Scene& scene, uint64_t triangles) {
  // Per world triangle: the surface record, atlas UVs, the BVH's leaf
  // triangle and about half a 4-wide node; then materials and textures
  // (4 bytes per texel, shading/texture_pack.h).
  const size_t per_triangle = sizeof(cl::LuxSurfaceTri) + sizeof(cl::LuxTriangleUV) +
                              sizeof(cl::LuxTriangle) + sizeof(cl::LuxBvh4Node) / 2;
  size_t bytes = static_cast<size_t>(triangles) * per_triangle +
                 scene.materials.size() * sizeof(cl::LuxMaterial);
  for (const scene::Texture& t : scene.textures) bytes += t.texel_count() * 4;
  return bytes;
}

}  // namespace

PathStateBytes path_state_bytes(bool basis_samples) {
  // BakeBuffers: two active lists, keys, paths, rays, hits, shadow rays,
  // shadow contributions, occlusion and alive flags, tagged slots, and with
  // directional encodings a basis sample; the radix sort's scratch keys and
  // values. Checked against BakeBuffers' dry run by resource_estimate_test.
  PathStateBytes b;
  b.per_path = 4 + 4 + 4 + sizeof(cl::LuxPath) + sizeof(cl::LuxRay) + sizeof(cl::LuxHit) +
               sizeof(cl::LuxRay) + 16 + 4 + 4 + 4 + 4 + 4;
  b.largest = sizeof(cl::LuxPath);
  if (basis_samples) {
    b.per_path += sizeof(cl::LuxBasisSample);
    b.largest = std::max(b.largest, sizeof(cl::LuxBasisSample));
  }
  return b;
}

size_t memory_budget(const BakeSettings& settings, uint64_t global_mem_bytes) {
  return settings.device_memory_budget_mib > 0
             ? static_cast<size_t>(settings.device_memory_budget_mib * 1048576.0)
             : default_memory_budget(global_mem_bytes);
}

Status check_path_state(uint64_t paths, const PathStateBytes& bytes, size_t other_fixed,
                        size_t budget, uint64_t max_alloc) {
  const double largest = static_cast<double>(paths) * static_cast<double>(bytes.largest);
  if (max_alloc > 0 && largest > static_cast<double>(max_alloc))
    return resource_exhausted(strprintf(
        "settings.paths_per_iteration: a batch of %llu paths needs one device buffer of %.0f "
        "bytes (%.0f MiB, %zu bytes per path), more than the device's largest allocation of "
        "%llu bytes (%.0f MiB); at most %llu paths per iteration fit",
        static_cast<unsigned long long>(paths), largest, mib(largest), bytes.largest,
        static_cast<unsigned long long>(max_alloc), mib(static_cast<double>(max_alloc)),
        static_cast<unsigned long long>(max_alloc / bytes.largest)));
  const double total = static_cast<double>(paths) * static_cast<double>(bytes.per_path);
  if (budget > 0 && total + static_cast<double>(other_fixed) >= static_cast<double>(budget))
    return resource_exhausted(strprintf(
        "settings.paths_per_iteration: a batch of %llu paths needs %.0f bytes (%.0f MiB, %zu "
        "bytes per path) of device memory that cannot be tiled%s, beyond the device-memory "
        "budget of %zu bytes (%.0f MiB, settings.device_memory_budget_mib); lower "
        "paths_per_iteration or raise the budget",
        static_cast<unsigned long long>(paths), total, mib(total), bytes.per_path,
        other_fixed > 0 ? strprintf(" beside %.1f MiB of scene", mib(other_fixed)).c_str() : "",
        budget, mib(static_cast<double>(budget))));
  return Status::ok();
}

uint64_t batch_paths_request(const BakeSettings& settings, const DeviceLimits& device,
                             const PathStateBytes& bytes, size_t budget) {
  constexpr uint64_t kCpuBatch = uint64_t{1} << 18, kGpuBatch = uint64_t{1} << 22;
  if (settings.paths_per_iteration > 0) return settings.paths_per_iteration;
  if (!device.is_gpu) return kCpuBatch;
  uint64_t batch = kGpuBatch;
  auto fits = [&](uint64_t paths) {
    const double total = static_cast<double>(paths) * static_cast<double>(bytes.per_path);
    const double largest = static_cast<double>(paths) * static_cast<double>(bytes.largest);
    return (budget == 0 || total <= 0.5 * static_cast<double>(budget)) &&
           (device.max_alloc_bytes == 0 || largest <= static_cast<double>(device.max_alloc_bytes));
  };
  while (batch > kCpuBatch && !fits(batch)) batch /= 2;
  return batch;
}

Result<ResourceEstimate> estimate_bake_resources(const scene::Scene& scene,
                                                 const BakeSettings& settings,
                                                 const DeviceLimits& device) {
  ResourceEstimate e;
  uint64_t triangles = 0;
  for (const scene::Instance& inst : scene.instances) {
    if (inst.mesh < 0 || static_cast<size_t>(inst.mesh) >= scene.meshes.size()) continue;
    const scene::Mesh& mesh = scene.meshes[static_cast<size_t>(inst.mesh)];
    triangles += mesh.indices.size() / 3;
    e.surface_area += atlas::instance_world_area(mesh, inst);
  }

  // The lightmap's texels. A chart's texels at density d cover at least its
  // world area x d^2 (shared atlases: side^2 >= area d^2 / uv area with uv
  // area <= 1; packed and generated charts: bounding rectangles of the
  // area scaled to d), so area x d^2 is a lower bound in every UV mode.
  const auto& as = settings.atlas;
  const int pages = pages_allowed(scene, settings);
  const double side = std::max(1, std::min(as.max_resolution, as.resolution_limit));
  e.max_texels = static_cast<uint64_t>(side * side * pages);
  if (as.resolution > 0) {
    e.min_texels = uint64_t(as.resolution) * uint64_t(as.resolution);
    e.max_texels = e.min_texels * static_cast<uint64_t>(pages);
  } else {
    const double d = as.texel_density;
    if (!(std::isfinite(d) && d > 0))
      return invalid_argument(
          strprintf("settings.texel_density: %g; give a finite density > 0 or a resolution", d));
    // Past what --max-resolution (and pages) allow, the layout lowers the
    // density to fit (atlas.h, uv/generate.h), so the lightmap is at most
    // that large.
    const double needed = std::min(e.surface_area * d * d, static_cast<double>(e.max_texels));
    e.min_texels = static_cast<uint64_t>(needed);
    // Covered texels: the charts' texels, less what rasterisation at chart
    // edges may leave out (half, to stay a lower bound).
    e.min_covered = static_cast<uint64_t>(needed / 2);
  }

  // The batch (bake_setup.cpp): paths_per_iteration within the device's
  // iteration cap, trimmed to the samples the whole bake needs when every
  // texel of the lightmap is covered.
  auto plan = plan_encodings(settings.encodings);
  if (!plan) return plan.status();
  e.per_path = path_state_bytes(!plan.value().empty());
  e.budget = memory_budget(settings, device.global_mem_bytes);
  const uint64_t requested = batch_paths_request(settings, device, e.per_path, e.budget);
  e.batch_paths = std::min<uint64_t>(requested, iteration_path_cap(device.compute_units));
  if (settings.samples_per_texel > 0)
    e.batch_paths = std::min<uint64_t>(
        e.batch_paths, static_cast<double>(settings.samples_per_texel) * e.max_texels > 4e18
                           ? e.batch_paths
                           : uint64_t{settings.samples_per_texel} * e.max_texels);
  e.path_bytes = static_cast<size_t>(e.batch_paths) * e.per_path.per_path;
  e.scene_bytes = scene_bytes(scene, triangles);
  e.per_texel_bytes = texel_state_bytes(plan.value().bytes_per_texel(), settings.adaptive,
                                        settings.radiance_cache, settings.guiding);
  if (Status st = check_path_state(e.batch_paths, e.per_path, e.scene_bytes, e.budget,
                                   device.max_alloc_bytes);
      !st.is_ok()) {
    if (e.batch_paths == requested) return st;
    return resource_exhausted(strprintf(
        "%s (paths_per_iteration %llu is trimmed to %llu paths by the device's iteration cap or "
        "the samples the bake needs)",
        st.message().c_str(), static_cast<unsigned long long>(requested),
        static_cast<unsigned long long>(e.batch_paths)));
  }
  // Per-texel state that cannot be tiled: the Gaussian filter (bake.cpp,
  // plan_memory) needs every covered texel at once.
  if (settings.filter == Filter::kGaussian && e.budget > 0 &&
      static_cast<double>(e.device_bytes(e.min_covered)) > static_cast<double>(e.budget))
    return resource_exhausted(strprintf(
        "settings.filter: 'gaussian' keeps the state of every texel on the device at once: at "
        "least %llu covered texels x %zu bytes beside %.0f MiB of batch and scene need %.0f MiB, "
        "more "
        "than the budget of %.0f MiB (settings.device_memory_budget_mib); use the box filter",
        static_cast<unsigned long long>(e.min_covered), e.per_texel_bytes,
        mib(static_cast<double>(e.scene_bytes + e.path_bytes)),
        mib(static_cast<double>(e.device_bytes(e.min_covered))),
        mib(static_cast<double>(e.budget))));
  return e;
}

}  // namespace luxel::pipeline
