#include "atlas/atlas.h"

#include <algorithm>
#include <cmath>

#include "atlas/chart_geometry.h"
#include "atlas/shelf_packer.h"
#include "atlas/texel_raster.h"

namespace luxel::atlas {
namespace {

// Grid on which the layouts of different instances are checked for shared UV
// space (see instances_share_uv_space).
constexpr int kOverlapCheckResolution = 1024;
// How far outside [0,1] a shared-mode UV may lie (float noise of exporters).
constexpr double kUvRangeTolerance = 1e-5;

// The largest page a texel density may give.
int page_limit(const AtlasSettings& s) {
  return std::min(s.max_resolution, s.resolution_limit);
}

// The file's TEXCOORD_1 lies on one page (a shared atlas cannot be cut, and
// the shelf packer fills one square), so a density that needs more is
// lowered to fit the page, as Unity scales down charts past its largest
// lightmap, and said.
std::string density_lowered(double asked, double achieved, int side) {
  return strprintf(
      "texel density lowered from %g to %.3g texels per unit to fit the file's TEXCOORD_1 on one "
      "%dx%d lightmap (--max-resolution); raise --max-resolution, or bake with --uv generate "
      "for several pages",
      asked, achieved, side, side);
}

Status check_settings(const AtlasSettings& s) {
  if (s.max_resolution < 1)
    return invalid_argument(
        strprintf("AtlasSettings.max_resolution is %d; it must be >= 1", s.max_resolution));
  if (s.resolution_limit < 1)
    return invalid_argument(
        strprintf("AtlasSettings.resolution_limit is %d; it must be >= 1", s.resolution_limit));
  if (s.padding_texels < 0)
    return invalid_argument(
        strprintf("AtlasSettings.padding_texels is %d; it must be >= 0", s.padding_texels));
  if (s.resolution < 0)
    return invalid_argument(strprintf(
        "AtlasSettings.resolution is %d; it must be >= 1 (or 0 to derive it from texel_density)",
        s.resolution));
  if (s.resolution > s.resolution_limit)
    return resource_exhausted(strprintf("resolution %d exceeds the largest lightmap side, %d",
                                        s.resolution, s.resolution_limit));
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
  bool lowered = false;
  if (side == 0) {
    const double d = settings.texel_density;
    const double needed = std::ceil(std::sqrt(world_area * d * d / uv_area));
    lowered = !(needed <= page_limit(settings));
    side = lowered ? page_limit(settings) : std::max(1, static_cast<int>(needed));
  }
  atlas.width = atlas.height = side;
  atlas.texels_per_unit = world_area > 0 ? std::sqrt(uv_area / world_area) * side : 0;
  if (lowered)
    atlas.warnings.push_back(density_lowered(settings.texel_density, atlas.texels_per_unit, side));
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
                                      page_limit(settings));
  Atlas atlas;
  if (!packed && packed.status().code() == StatusCode::kResourceExhausted &&
      settings.resolution == 0) {
    // Past the page: the largest density that fits it.
    packed = pack_at_resolution(extents, page_limit(settings), settings.padding_texels);
    if (packed)
      atlas.warnings.push_back(
          density_lowered(settings.texel_density, packed.value().density, packed.value().side));
  }
  if (!packed) return packed.status();
  const PackedLayout& layout = packed.value();
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

// No texel centre inside triangles of two different instances (placed
// layouts come from the client, so they are checked, not trusted).
Status check_instances_disjoint(const scene::Scene& scene, const Atlas& atlas) {
  std::vector<int32_t> owner(size_t(atlas.width) * size_t(atlas.height), -1);
  for (uint32_t i = 0; i < scene.instances.size(); ++i) {
    const scene::Mesh& mesh = scene.meshes[static_cast<size_t>(scene.instances[i].mesh)];
    for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
      const TexelTriangle tt = texel_triangle(scene, atlas, i, t);
      const double x0 = std::min({tt.x[0], tt.x[1], tt.x[2]}),
                   x1 = std::max({tt.x[0], tt.x[1], tt.x[2]});
      const double y0 = std::min({tt.y[0], tt.y[1], tt.y[2]}),
                   y1 = std::max({tt.y[0], tt.y[1], tt.y[2]});
      auto edge = [&](int a, int b, double px, double py) {
        return (tt.x[b] - tt.x[a]) * (py - tt.y[a]) - (tt.y[b] - tt.y[a]) * (px - tt.x[a]);
      };
      const int ya = std::max(0, static_cast<int>(std::ceil(y0 - 0.5)));
      const int yb = std::min(atlas.height - 1, static_cast<int>(std::floor(y1 - 0.5)));
      const int xa = std::max(0, static_cast<int>(std::ceil(x0 - 0.5)));
      const int xb = std::min(atlas.width - 1, static_cast<int>(std::floor(x1 - 0.5)));
      for (int y = ya; y <= yb; ++y) {
        for (int x = xa; x <= xb; ++x) {
          const double px = x + 0.5, py = y + 0.5;
          const double e0 = edge(0, 1, px, py), e1 = edge(1, 2, px, py), e2 = edge(2, 0, px, py);
          const bool inside = (e0 > 0 && e1 > 0 && e2 > 0) || (e0 < 0 && e1 < 0 && e2 < 0);
          if (!inside) continue;
          int32_t& o = owner[size_t(y) * size_t(atlas.width) + size_t(x)];
          if (o >= 0 && o != static_cast<int32_t>(i))
            return invalid_argument(strprintf(
                "the lightmap placements of instances '%s' and '%s' overlap (texel %d, %d of the "
                "%dx%d atlas; extras.lightmapScaleOffset)",
                scene.instances[static_cast<size_t>(o)].name.c_str(),
                scene.instances[i].name.c_str(), x, y, atlas.width, atlas.height));
          o = static_cast<int32_t>(i);
        }
      }
    }
  }
  return Status::ok();
}

// Every instance where its node's extras.lightmapScaleOffset puts it.
Result<Atlas> build_placed(const scene::Scene& scene, const std::vector<InstanceChart>& charts,
                           const AtlasSettings& settings) {
  for (const auto& inst : scene.instances)
    if (!inst.has_lightmap_scale_offset)
      return invalid_argument(strprintf(
          "instance '%s' has no extras.lightmapScaleOffset while other nodes do; give every "
          "baked node one, or none (to have Luxel pack the atlas)",
          inst.name.c_str()));
  Atlas atlas;
  atlas.mode = AtlasMode::kPlaced;
  for (const auto& inst : scene.instances)
    atlas.pages = std::max(atlas.pages, inst.lightmap_page + 1);
  double world_area = 0, atlas_uv_area = 0;
  for (size_t i = 0; i < charts.size(); ++i) {
    const float* so = scene.instances[i].lightmap_scale_offset;
    world_area += charts[i].world_area;
    atlas_uv_area += charts[i].layout->area * std::fabs(double(so[0]) * so[1]);
  }
  int side = settings.resolution;
  // Several pages: each is the resolution given, or max_resolution (the page
  // size of generated layouts).
  if (side == 0 && atlas.pages > 1) side = page_limit(settings);
  bool lowered = false;
  if (side == 0) {
    const double d = settings.texel_density;
    const double needed = std::ceil(std::sqrt(world_area * d * d / atlas_uv_area));
    lowered = !(needed <= page_limit(settings));
    side = lowered ? page_limit(settings) : std::max(1, static_cast<int>(needed));
  }
  atlas.width = atlas.height = side;
  atlas.texels_per_unit = world_area > 0 ? std::sqrt(atlas_uv_area / world_area) * side : 0;
  if (lowered)
    atlas.warnings.push_back(density_lowered(settings.texel_density, atlas.texels_per_unit, side));
  atlas.height = side * atlas.pages;  // pages stacked from the top
  for (size_t i = 0; i < charts.size(); ++i) {
    const float* so = scene.instances[i].lightmap_scale_offset;
    InstancePlacement p;
    p.instance = static_cast<uint32_t>(i);
    p.page = scene.instances[i].lightmap_page;
    p.scale[0] = so[0];
    p.scale[1] = so[1];
    p.offset[0] = so[2];
    p.offset[1] = so[3];
    if (atlas.pages > 1) {
      // The page's scale/offset into the stacked image (the inverse of
      // page_relative).
      p.scale[1] = static_cast<float>(double(so[1]) / atlas.pages);
      p.offset[1] = static_cast<float>((double(so[3]) + p.page) / atlas.pages);
    }
    const UvBounds& b = charts[i].layout->bounds;
    double lo[2], hi[2];
    for (int a = 0; a < 2; ++a) {
      // On the instance's own page, in texels.
      const double e0 = (b.lo[a] * so[a] + so[2 + a]) * side;
      const double e1 = (b.hi[a] * so[a] + so[2 + a]) * side;
      lo[a] = std::min(e0, e1);
      hi[a] = std::max(e0, e1);
      if (lo[a] < -1e-3 || hi[a] > side + 1e-3)
        return invalid_argument(strprintf(
            "instance '%s': extras.lightmapScaleOffset puts its lightmap UVs outside the atlas "
            "(texels %.1f..%.1f on axis %c of %d)",
            scene.instances[i].name.c_str(), lo[a], hi[a], a == 0 ? 'x' : 'y', side));
    }
    p.rect[0] = static_cast<int>(std::floor(lo[0]));
    p.rect[1] = static_cast<int>(std::floor(lo[1]));
    p.rect[2] = std::min(side - p.rect[0], static_cast<int>(std::ceil(hi[0])) - p.rect[0]);
    p.rect[3] = std::min(side - p.rect[1], static_cast<int>(std::ceil(hi[1])) - p.rect[1]);
    p.rect[1] += side * p.page;
    atlas.placements.push_back(p);
  }
  LUXEL_RETURN_IF_ERROR(check_instances_disjoint(scene, atlas));
  return atlas;
}

}  // namespace

const char* atlas_mode_name(AtlasMode mode) {
  switch (mode) {
    case AtlasMode::kPacked:
      return "packed";
    case AtlasMode::kGenerated:
      return "generated";
    case AtlasMode::kPlaced:
      return "placed";
    case AtlasMode::kShared:
      break;
  }
  return "shared";
}

Result<Atlas> build_atlas(const scene::Scene& scene, const AtlasSettings& settings) {
  LUXEL_RETURN_IF_ERROR(check_settings(settings));
  if (scene.instances.empty())
    return invalid_argument(
        "scene has no geometry: no mesh instance with triangles to bake (only triangles "
        "are lightmapped, not points or lines)");
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
  const size_t placed = static_cast<size_t>(
      std::count_if(scene.instances.begin(), scene.instances.end(),
                    [](const scene::Instance& i) { return i.has_lightmap_scale_offset; }));
  if (placed > 0) return build_placed(scene, charts, settings);
  const bool single_use = std::all_of(uses.begin(), uses.end(), [](int n) { return n <= 1; });
  if (single_use && !instances_share_uv_space(scene, kOverlapCheckResolution))
    return build_shared(scene, charts, settings);
  return build_packed(charts, settings);
}

}  // namespace luxel::atlas
