#include "atlas/atlas.h"

#include <algorithm>
#include <cmath>

#include "atlas/chart_geometry.h"
#include "atlas/shelf_packer.h"

namespace luxel::atlas {
namespace {

// Grid on which the layouts of different instances are checked for shared UV
// space (see instances_share_uv_space).
constexpr int kOverlapCheckResolution = 1024;
// How far outside [0,1] a shared-mode UV may lie (float noise of exporters).
constexpr double kUvRangeTolerance = 1e-5;

Status check_settings(const AtlasSettings& s) {
  if (s.max_resolution < 1)
    return invalid_argument(
        strprintf("AtlasSettings.max_resolution is %d; it must be >= 1", s.max_resolution));
  if (s.padding_texels < 0)
    return invalid_argument(
        strprintf("AtlasSettings.padding_texels is %d; it must be >= 0", s.padding_texels));
  if (s.resolution < 0)
    return invalid_argument(strprintf(
        "AtlasSettings.resolution is %d; it must be >= 1 (or 0 to derive it from texel_density)",
        s.resolution));
  if (s.resolution > s.max_resolution)
    return resource_exhausted(strprintf("AtlasSettings.resolution %d exceeds max_resolution %d",
                                        s.resolution, s.max_resolution));
  if (s.resolution == 0 && !(std::isfinite(s.texel_density) && s.texel_density > 0))
    return invalid_argument(
        strprintf("AtlasSettings.texel_density is %g with resolution 0; set a resolution >= 1 or a "
                  "finite texel_density > 0 (texels per world unit)",
                  static_cast<double>(s.texel_density)));
  return Status::ok();
}

struct InstanceChart {
  const MeshUvLayout* layout = nullptr;
  double world_area = 0;
};

Status check_unit_square(const scene::Scene& scene, const std::vector<InstanceChart>& charts) {
  for (size_t i = 0; i < charts.size(); ++i) {
    const UvBounds& b = charts[i].layout->bounds;
    if (b.lo[0] < -kUvRangeTolerance || b.lo[1] < -kUvRangeTolerance ||
        b.hi[0] > 1 + kUvRangeTolerance || b.hi[1] > 1 + kUvRangeTolerance) {
      const auto& mesh = scene.meshes[static_cast<size_t>(scene.instances[i].mesh)];
      return invalid_argument(strprintf(
          "mesh '%s': TEXCOORD_1 spans [%g, %g] x [%g, %g], outside the unit square of the "
          "scene-wide lightmap atlas (charts would be clipped)",
          mesh.name.c_str(), b.lo[0], b.hi[0], b.lo[1], b.hi[1]));
    }
  }
  return Status::ok();
}

Result<Atlas> build_shared(const scene::Scene& scene, const std::vector<InstanceChart>& charts,
                           const AtlasSettings& settings) {
  LUXEL_RETURN_IF_ERROR(check_unit_square(scene, charts));
  double world_area = 0, uv_area = 0;
  for (const auto& c : charts) {
    world_area += c.world_area;
    uv_area += c.layout->area;
  }
  Atlas atlas;
  atlas.mode = AtlasMode::kShared;
  int side = settings.resolution;
  if (side == 0) {
    const double d = settings.texel_density;
    const double needed = std::ceil(std::sqrt(world_area * d * d / uv_area));
    if (!(needed <= settings.max_resolution))
      return resource_exhausted(
          strprintf("texel_density %g needs a %.0fx%.0f lightmap atlas; max_resolution is %d", d,
                    needed, needed, settings.max_resolution));
    side = std::max(1, static_cast<int>(needed));
  }
  atlas.width = atlas.height = side;
  atlas.texels_per_unit = world_area > 0 ? std::sqrt(uv_area / world_area) * side : 0;
  for (size_t i = 0; i < charts.size(); ++i) {
    InstancePlacement p;
    p.instance = static_cast<uint32_t>(i);
    p.rect[2] = p.rect[3] = side;
    atlas.placements.push_back(p);
  }
  return atlas;
}

Result<Atlas> build_packed(const std::vector<InstanceChart>& charts,
                           const AtlasSettings& settings) {
  std::vector<ChartExtent> extents;
  for (const auto& c : charts) {
    ChartExtent e;
    e.uv_width = c.layout->bounds.width();
    e.uv_height = c.layout->bounds.height();
    e.stretch = std::sqrt(c.world_area / c.layout->area);
    extents.push_back(e);
  }
  auto packed = settings.resolution > 0
                    ? pack_at_resolution(extents, settings.resolution, settings.padding_texels)
                    : pack_at_density(extents, settings.texel_density, settings.padding_texels,
                                      settings.max_resolution);
  if (!packed) return packed.status();
  const PackedLayout& layout = packed.value();
  Atlas atlas;
  atlas.mode = AtlasMode::kPacked;
  atlas.width = atlas.height = layout.side;
  atlas.texels_per_unit = layout.density;
  const double side = layout.side;
  for (size_t i = 0; i < charts.size(); ++i) {
    const auto& r = layout.rects[i];
    const double s = layout.texels_per_uv[i];
    const UvBounds& b = charts[i].layout->bounds;
    InstancePlacement p;
    p.instance = static_cast<uint32_t>(i);
    for (int axis = 0; axis < 2; ++axis) {
      p.scale[axis] = static_cast<float>(s / side);
      const double start = r[static_cast<size_t>(axis)] + kChartInsetTexels;
      p.offset[axis] = static_cast<float>((start - b.lo[axis] * s) / side);
    }
    std::copy(r.begin(), r.end(), p.rect);
    atlas.placements.push_back(p);
  }
  return atlas;
}

}  // namespace

const char* atlas_mode_name(AtlasMode mode) {
  return mode == AtlasMode::kShared ? "shared" : "packed";
}

Result<Atlas> build_atlas(const scene::Scene& scene, const AtlasSettings& settings) {
  LUXEL_RETURN_IF_ERROR(check_settings(settings));
  if (scene.instances.empty())
    return invalid_argument("scene has no geometry: it has no mesh instances to bake");
  std::vector<int> uses(scene.meshes.size(), 0);
  for (const auto& inst : scene.instances) {
    if (inst.mesh < 0 || static_cast<size_t>(inst.mesh) >= scene.meshes.size())
      return invalid_argument(strprintf("instance '%s' refers to mesh %d of %zu", inst.name.c_str(),
                                        inst.mesh, scene.meshes.size()));
    ++uses[static_cast<size_t>(inst.mesh)];
  }
  // Only meshes that are instanced are laid out (and validated).
  std::vector<MeshUvLayout> layouts(scene.meshes.size());
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    if (uses[m] == 0) continue;
    auto layout = measure_mesh_uvs(scene.meshes[m]);
    if (!layout) return layout.status();
    layouts[m] = layout.value();
  }
  std::vector<InstanceChart> charts;
  for (const auto& inst : scene.instances) {
    const auto m = static_cast<size_t>(inst.mesh);
    const double area = instance_world_area(scene.meshes[m], inst);
    if (!std::isfinite(area))
      return invalid_argument(strprintf("instance '%s' of mesh '%s' has a non-finite world area",
                                        inst.name.c_str(), scene.meshes[m].name.c_str()));
    charts.push_back({&layouts[m], area});
  }
  const bool single_use = std::all_of(uses.begin(), uses.end(), [](int n) { return n <= 1; });
  if (single_use && !instances_share_uv_space(scene, kOverlapCheckResolution))
    return build_shared(scene, charts, settings);
  return build_packed(charts, settings);
}

}  // namespace luxel::atlas
