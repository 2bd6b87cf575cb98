#include "uv/generate.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>

#include "atlas/chart_geometry.h"
#include "common/clock.h"
#include "scene/uv_raster.h"
#include "uv/bitimage_packer.h"
#include "uv/generate_layout.h"
#include "uv/stretch.h"

namespace luxel::uv {
namespace {

// World-space area of a set of a mesh's triangles under one instance.
double world_area(const scene::Mesh& mesh, const Mat4& m, const std::vector<uint32_t>& triangles) {
  auto world = [&](uint32_t index, double out[3]) {
    const Vec3 p = mesh.positions[index];
    for (int r = 0; r < 3; ++r)
      out[r] = m.at(r, 0) * p.x + m.at(r, 1) * p.y + m.at(r, 2) * p.z + m.at(r, 3);
  };
  double area = 0;
  for (uint32_t t : triangles) {
    double a[3], b[3], c[3];
    world(mesh.indices[t * 3], a);
    world(mesh.indices[t * 3 + 1], b);
    world(mesh.indices[t * 3 + 2], c);
    const double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double x = e1[1] * e2[2] - e1[2] * e2[1];
    const double y = e1[2] * e2[0] - e1[0] * e2[2];
    const double z = e1[0] * e2[1] - e1[1] * e2[0];
    area += 0.5 * std::sqrt(x * x + y * y + z * z);
  }
  return area;
}

// Points and lines have no area to hold texels (glTF modes 0-3).
Status no_triangles() {
  return invalid_argument(
      "the scene has no triangle that can be laid out: only triangles are lightmapped, not "
      "points or lines");
}

PackShape chart_shape(const Chart& chart, double scale, bool allow_rotation) {
  PackShape s;
  s.allow_rotation = allow_rotation;
  s.corners.reserve(chart.indices.size());
  for (uint32_t i : chart.indices) {
    const Vec2 p = chart.uv[i];
    s.corners.push_back({static_cast<float>(p.x * scale), static_cast<float>(p.y * scale)});
  }
  return s;
}

// The shapes of every baked mesh at `density` texels per world unit (each
// instanced mesh's own layout packed on the way), with their sources.
Status build_shapes(const std::vector<MeshCharts>& meshes, double density, const PackOptions& pack,
                    PackAttempt* out, std::vector<PackShape>* out_shapes) {
  PackAttempt& a = *out;
  std::vector<PackShape>& shapes = *out_shapes;
  a.layouts.resize(meshes.size());
  for (uint32_t m = 0; m < meshes.size(); ++m) {
    const MeshCharts& mc = meshes[m];
    if (mc.instances.empty() || mc.charts.empty()) continue;
    if (mc.instances.size() == 1) {
      for (uint32_t c = 0; c < mc.charts.size(); ++c) {
        shapes.push_back(chart_shape(mc.charts[c], density * mc.chart_scale[c], true));
        a.sources.push_back({m, c, -1});
      }
      continue;
    }
    // The mesh's own layout at its smallest instance's scale.
    MeshLayout& layout = a.layouts[m];
    layout.scale = density * mc.layout_scale;
    std::vector<PackShape> own;
    for (const Chart& c : mc.charts) own.push_back(chart_shape(c, layout.scale, true));
    PackOptions own_options;
    own_options.padding_texels = pack.padding_texels;
    own_options.max_resolution = pack.max_resolution;
    auto packed = pack_shapes(own, own_options);
    if (!packed) return packed.status();
    layout.width = packed.value().width;
    layout.height = packed.value().height;
    layout.placements = std::move(packed.value().placements);
    // Each instance: the whole layout, scaled up to its own size, unturned
    // (a placement is a scale and an offset only).
    for (uint32_t k = 0; k < mc.instances.size(); ++k) {
      const double grow = mc.grow(k);
      PackShape s;
      s.allow_rotation = false;
      for (uint32_t c = 0; c < mc.charts.size(); ++c) {
        const Chart& chart = mc.charts[c];
        for (uint32_t i : chart.indices) {
          const DPoint p = placed_point(chart.uv[i].x * layout.scale, chart.uv[i].y * layout.scale,
                                        layout.placements[c]);
          s.corners.push_back({static_cast<float>(p.x * grow), static_cast<float>(p.y * grow)});
        }
      }
      shapes.push_back(std::move(s));
      a.sources.push_back({m, 0, static_cast<int32_t>(mc.instances[k])});
    }
  }
  if (shapes.empty()) return no_triangles();
  return Status::ok();
}

// Packs every baked mesh at `density` texels per world unit into the atlas
// size of `pack` (0: the smallest that fits).
Result<PackAttempt> pack_at(const std::vector<MeshCharts>& meshes, double density,
                            const PackOptions& pack) {
  PackAttempt a;
  std::vector<PackShape> shapes;
  LUXEL_RETURN_IF_ERROR(build_shapes(meshes, density, pack, &a, &shapes));
  auto packed = pack_shapes(shapes, pack);
  if (!packed) return packed.status();
  a.pack = std::move(packed.value());
  a.page.assign(shapes.size(), 0);
  return a;
}

// Measured on the final UVs, so the report checks the whole chain: texel
// centres of the laid-out atlas inside two or more triangles of any
// instances (the packer's conservative masks make it 0), and the spread of
// the achieved texel density, sqrt(texel area / world area) per instance.
// One page at a time, so memory stays that of one page.
void measure_layout(const scene::Scene& scene, const atlas::Atlas& at, UvReport* report) {
  size_t overlaps = 0;
  double lo = std::numeric_limits<double>::infinity(), hi = 0;
  const int page_h = at.page_height();
  scene::UvRaster raster(at.width, page_h);
  std::vector<uint32_t> all;
  for (int page = 0; page < at.pages; ++page) {
    for (const atlas::InstancePlacement& stacked : at.placements) {
      if (stacked.page != page) continue;
      const atlas::InstancePlacement p = atlas::page_relative(at, stacked);
      const scene::Instance& inst = scene.instances[p.instance];
      const scene::Mesh& m = scene.meshes[static_cast<size_t>(inst.mesh)];
      if (m.uv1.size() != m.positions.size() || m.triangle_count() == 0) continue;
      auto to_page = [&](uint32_t v) {
        const Vec2 uv = m.uv1[v];
        return Vec2{uv.x * p.scale[0] + p.offset[0], uv.y * p.scale[1] + p.offset[1]};
      };
      double texel_area = 0;
      for (size_t t = 0; t < m.triangle_count(); ++t) {
        const Vec2 a = to_page(m.indices[3 * t]), b = to_page(m.indices[3 * t + 1]),
                   c = to_page(m.indices[3 * t + 2]);
        raster.add(a, b, c);
        texel_area += 0.5 *
                      std::fabs(double(b.x - a.x) * double(c.y - a.y) -
                                double(c.x - a.x) * double(b.y - a.y)) *
                      at.width * page_h;
      }
      all.resize(m.triangle_count());
      for (uint32_t t = 0; t < all.size(); ++t) all[t] = t;
      const double world = world_area(m, inst.object_to_world, all);
      if (world > 0 && texel_area > 0) {
        const double density = std::sqrt(texel_area / world);
        lo = std::min(lo, density);
        hi = std::max(hi, density);
      }
    }
    raster.resolve([&](size_t, int32_t count) { overlaps += count > 1; });
  }
  report->overlapping_texels = overlaps;
  report->density_spread = hi > 0 ? hi / lo : 1;
}

// The instance a shape belongs to: a page holds whole instances, so that
// each instance has one page and one scale/offset.
uint32_t shape_instance(const std::vector<MeshCharts>& meshes, const ShapeSource& s) {
  return s.instance >= 0 ? static_cast<uint32_t>(s.instance) : meshes[s.mesh].instances[0];
}

// Lightmap arrays (as Unity's and Unreal's): when `density` needs more than
// one max_resolution square, instances are dealt to pages of that size,
// largest first, each page filled to an estimated 80 % of its area and
// packed; an instance that does not fit moves to the next page. Placements
// come back in page texels with a page per shape.
Result<PackAttempt> pack_pages(const std::vector<MeshCharts>& meshes, double density,
                               const PackOptions& pack, int max_pages) {
  PackAttempt a;
  std::vector<PackShape> shapes;
  LUXEL_RETURN_IF_ERROR(build_shapes(meshes, density, pack, &a, &shapes));
  const int side = pack.max_resolution;
  // Per instance: its shapes and their estimated footprint (bounding boxes
  // grown by the padding).
  std::map<uint32_t, std::vector<size_t>> by_instance;
  std::map<uint32_t, double> footprint;
  for (size_t i = 0; i < shapes.size(); ++i) {
    const uint32_t inst = shape_instance(meshes, a.sources[i]);
    by_instance[inst].push_back(i);
    float lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (const Vec2& c : shapes[i].corners) {
      lo[0] = std::min(lo[0], c.x), hi[0] = std::max(hi[0], c.x);
      lo[1] = std::min(lo[1], c.y), hi[1] = std::max(hi[1], c.y);
    }
    footprint[inst] +=
        (hi[0] - lo[0] + 1 + pack.padding_texels) * (hi[1] - lo[1] + 1 + pack.padding_texels);
  }
  std::vector<uint32_t> order;
  for (const auto& [inst, list] : by_instance) order.push_back(inst);
  std::stable_sort(order.begin(), order.end(),
                   [&](uint32_t x, uint32_t y) { return footprint[x] > footprint[y]; });
  const double budget = 0.8 * double(side) * double(side);
  std::vector<std::vector<uint32_t>> pages;
  std::vector<double> filled;
  for (uint32_t inst : order) {
    size_t p = 0;
    while (p < pages.size() && filled[p] + footprint[inst] > budget) ++p;
    if (p == pages.size()) {
      pages.emplace_back();
      filled.push_back(0);
    }
    pages[p].push_back(inst);
    filled[p] += footprint[inst];
  }
  a.page.assign(shapes.size(), -1);
  a.pack.placements.assign(shapes.size(), ShapePlacement{});
  a.pack.width = side;
  a.pack.height = side;
  long long covered = 0;
  PackOptions fixed = pack;
  fixed.width = fixed.height = side;
  for (size_t p = 0; p < pages.size(); ++p) {
    if (static_cast<int>(p) >= max_pages)
      return resource_exhausted(
          strprintf("the lightmap needs more than %d pages of %dx%d at %g texels per unit; lower "
                    "--texel-density or raise --max-resolution",
                    max_pages, side, side, density));
    while (true) {
      std::vector<PackShape> page_shapes;
      std::vector<size_t> index;
      for (uint32_t inst : pages[p])
        for (size_t i : by_instance[inst]) {
          page_shapes.push_back(shapes[i]);
          index.push_back(i);
        }
      auto packed = pack_shapes(page_shapes, fixed);
      if (packed) {
        for (size_t k = 0; k < index.size(); ++k) {
          a.pack.placements[index[k]] = packed.value().placements[k];
          a.page[index[k]] = static_cast<int>(p);
        }
        covered += packed.value().covered_texels;
        break;
      }
      if (packed.status().code() != StatusCode::kResourceExhausted) return packed.status();
      if (pages[p].size() == 1)
        return resource_exhausted(strprintf(
            "instance %u alone does not fit one %dx%d lightmap page at %g texels per unit; lower "
            "--texel-density or raise --max-resolution (or --resolution)",
            pages[p][0], side, side, density));
      // The smallest instance of the page moves on to the next page.
      if (p + 1 == pages.size()) pages.emplace_back();
      pages[p + 1].insert(pages[p + 1].begin(), pages[p].back());
      pages[p].pop_back();
    }
  }
  a.pages = static_cast<int>(pages.size());
  a.pack.covered_texels = covered;
  a.pack.efficiency = double(covered) / (double(side) * double(side) * a.pages);
  return a;
}

// Area-weighted texels per world unit the charts would need at density 1.
double total_world_area(const std::vector<MeshCharts>& meshes) {
  double area = 0;
  for (const MeshCharts& mc : meshes) {
    if (mc.instances.empty()) continue;
    if (mc.instances.size() == 1) {
      for (size_t c = 0; c < mc.charts.size(); ++c)
        area += mc.charts[c].area_3d * mc.chart_scale[c] * mc.chart_scale[c];
    } else {
      double mesh_area = 0;
      for (const Chart& c : mc.charts) mesh_area += c.area_3d;
      for (double s : mc.instance_scale) {
        const double placed = std::max(s, mc.layout_scale);
        area += mesh_area * placed * placed;
      }
    }
  }
  return area;
}

// The longest side, in texels at density 1, of any shape the packer will
// get (a chart's UV bounding box, or an instance's whole layout, roughly).
double longest_shape_extent(const std::vector<MeshCharts>& meshes) {
  double longest = 0;
  for (const MeshCharts& mc : meshes) {
    if (mc.instances.empty()) continue;
    double largest_instance = 0;
    for (size_t k = 0; k < mc.instance_scale.size(); ++k)
      largest_instance = std::max(largest_instance, mc.layout_scale * mc.grow(k));
    for (size_t c = 0; c < mc.charts.size(); ++c) {
      const Chart& chart = mc.charts[c];
      float lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
      for (const Vec2& p : chart.uv) {
        lo[0] = std::min(lo[0], p.x), hi[0] = std::max(hi[0], p.x);
        lo[1] = std::min(lo[1], p.y), hi[1] = std::max(hi[1], p.y);
      }
      const double scale = mc.instances.size() == 1 ? mc.chart_scale[c] : largest_instance;
      longest = std::max(longest, std::max(hi[0] - lo[0], hi[1] - lo[1]) * scale);
    }
  }
  return longest;
}

// The largest density whose packing fits `side` (within about 3 %); when
// none does, several pages of side x side.
Result<std::pair<double, PackAttempt>> fit_resolution(const std::vector<MeshCharts>& meshes,
                                                      int side, const PackOptions& base,
                                                      int max_pages, int* attempts) {
  const double area = total_world_area(meshes);
  if (!(area > 0)) return no_triangles();
  // First guess: the packer's automatic square at a density that fills the
  // side at 70 % efficiency, then scaled by how far off it came out.
  // No shape may be longer than the side: long slivers bound the density
  // where area alone would ask the probe for an atlas of gigabytes.
  double density = side * std::sqrt(0.7 / area);
  const double longest = longest_shape_extent(meshes);
  if (longest > 0) density = std::min(density, 0.9 * side / longest);
  // The probe's automatic square is bounded too; past it, a quarter of the
  // density and again.
  PackOptions automatic = base;
  automatic.max_resolution = static_cast<int>(std::min<int64_t>(int64_t{side} * 16, 1 << 20));
  Result<PackAttempt> probe = resource_exhausted("no probe");
  for (int tries = 0; tries < 8; ++tries) {
    ++*attempts;
    probe = pack_at(meshes, density, automatic);
    if (probe || probe.status().code() != StatusCode::kResourceExhausted) break;
    density *= 0.25;
  }
  if (!probe) return probe.status();
  const int probe_side = std::max(probe.value().pack.width, probe.value().pack.height);
  density *= 0.995 * side / probe_side;
  PackOptions fixed = base;
  fixed.width = fixed.height = side;
  for (int i = 0; i < 24; ++i) {
    ++*attempts;
    auto a = pack_at(meshes, density, fixed);
    if (a) return std::make_pair(density, std::move(a.value()));
    if (a.status().code() != StatusCode::kResourceExhausted) return a.status();
    density *= 0.97;
  }
  // Every chart keeps at least one texel and its padding, so on a small
  // side many charts fit at no density: they go on several pages of the
  // side asked (whole instances per page, as past max_resolution), at the
  // density reached, halved while an instance alone is too large.
  PackOptions paged = base;
  paged.max_resolution = side;
  Result<PackAttempt> pages = resource_exhausted("no pages");
  for (int i = 0; i < 6 && max_pages > 1; ++i) {
    ++*attempts;
    pages = pack_pages(meshes, density, paged, max_pages);
    if (pages) return std::make_pair(density, std::move(pages.value()));
    if (pages.status().code() != StatusCode::kResourceExhausted) return pages.status();
    density *= 0.5;
  }
  return resource_exhausted(
      strprintf("the charts do not fit %d page(s) of %dx%d at any density tried (down to %g "
                "texels per unit); raise --resolution",
                std::max(1, max_pages), side, side, density));
}

// Past the most pages, the density that fits them: first scaled by the
// texels asked over the pages' capacity at the packer's usual 70 %
// efficiency, then lowered in steps. The warning says by how much.
Result<PackAttempt> pack_pages_lowering(const std::vector<MeshCharts>& meshes, double& density,
                                        const PackOptions& pack, int max_pages, int* attempts,
                                        std::vector<std::string>& warnings) {
  const double asked = density;
  const double side = pack.max_resolution;
  const double capacity = 0.7 * side * side * max_pages;
  const double needed = total_world_area(meshes) * density * density;
  if (needed > capacity) density *= std::sqrt(capacity / needed);
  Result<PackAttempt> a = resource_exhausted("no pages");
  for (int i = 0; i < 8; ++i) {
    ++*attempts;
    a = pack_pages(meshes, density, pack, max_pages);
    if (a || a.status().code() != StatusCode::kResourceExhausted) break;
    density *= 0.85;
  }
  if (a && density < asked)
    warnings.push_back(
        strprintf("texel density lowered from %g to %.3g texels per unit to fit pages of %dx%d "
                  "(--max-resolution; each instance on one page, at most %d pages); raise "
                  "--max-resolution for more texels",
                  asked, density, pack.max_resolution, pack.max_resolution, max_pages));
  return a;
}

// 1. Charts of every instanced mesh, and their world scales.
Result<std::vector<MeshCharts>> chart_meshes(const scene::Scene& scene,
                                             const GenerateOptions& options) {
  std::vector<MeshCharts> meshes(scene.meshes.size());
  for (uint32_t i = 0; i < scene.instances.size(); ++i) {
    const int m = scene.instances[i].mesh;
    if (m < 0 || static_cast<size_t>(m) >= scene.meshes.size())
      return invalid_argument(strprintf("instance '%s' refers to mesh %d of %zu",
                                        scene.instances[i].name.c_str(), m, scene.meshes.size()));
    meshes[static_cast<size_t>(m)].instances.push_back(i);
  }
  for (uint32_t m = 0; m < meshes.size(); ++m) {
    MeshCharts& mc = meshes[m];
    if (mc.instances.empty()) continue;
    LUXEL_RETURN_IF_ERROR(check_cancel(options.cancel, "UV charting"));
    const scene::Mesh& mesh = scene.meshes[m];
    auto charts = build_charts(mesh, options.charts);
    if (!charts) return charts.status();
    mc.charts = std::move(charts.value());
    double mesh_area = 0;
    for (const Chart& c : mc.charts) mesh_area += c.area_3d;
    if (mc.charts.empty() || !(mesh_area > 0)) {
      mc.charts.clear();
      continue;
    }
    if (mc.instances.size() == 1) {
      const Mat4& xf = scene.instances[mc.instances[0]].object_to_world;
      for (const Chart& c : mc.charts) {
        const double w = world_area(mesh, xf, c.triangles);
        mc.chart_scale.push_back(c.area_3d > 0 && w > 0 ? std::sqrt(w / c.area_3d) : 0);
      }
    } else {
      std::vector<uint32_t> all;
      for (const Chart& c : mc.charts)
        all.insert(all.end(), c.triangles.begin(), c.triangles.end());
      double smallest = std::numeric_limits<double>::infinity(), largest = 0;
      for (uint32_t inst : mc.instances) {
        const double w = world_area(mesh, scene.instances[inst].object_to_world, all);
        const double s = std::sqrt(w / mesh_area);
        if (!(std::isfinite(s) && s > 0))
          return invalid_argument(
              strprintf("instance '%s' of mesh '%s' has a zero or non-finite world area",
                        scene.instances[inst].name.c_str(), mesh.name.c_str()));
        mc.instance_scale.push_back(s);
        smallest = std::min(smallest, s);
        largest = std::max(largest, s);
      }
      mc.layout_scale = std::max(smallest, largest / MeshCharts::kMaxGrow);
    }
    for (size_t c = 0; c < mc.charts.size(); ++c)
      if (!(std::isfinite(mc.chart_scale.empty() ? 1.0 : mc.chart_scale[c])))
        return invalid_argument(
            strprintf("mesh '%s' has a non-finite world area", mesh.name.c_str()));
  }
  return meshes;
}

// 2. Packing at one density: the density that fills the requested
// resolution, or the requested density (on several pages when one
// max_resolution square is too small).
Result<PackAttempt> pack_meshes(const std::vector<MeshCharts>& meshes,
                                const GenerateOptions& options, double& density, UvReport& report,
                                std::vector<std::string>& warnings) {
  const atlas::AtlasSettings& as = options.atlas;
  PackOptions pack;
  pack.padding_texels = as.padding_texels;
  pack.cancel = options.cancel;
  // A density's pages are at most max_resolution; a resolution asked is the
  // page itself, and the instanced meshes' own layouts may grow to the limit.
  pack.max_resolution = as.resolution > 0 ? std::max(as.resolution_limit, as.resolution)
                                          : std::min(as.max_resolution, as.resolution_limit);
  density = as.texel_density;
  PackAttempt attempt;
  if (as.resolution > 0) {
    auto fitted =
        fit_resolution(meshes, as.resolution, pack, options.max_pages, &report.pack_attempts);
    if (!fitted) return fitted.status();
    density = fitted.value().first;
    attempt = std::move(fitted.value().second);
    if (attempt.pages > 1)
      warnings.push_back(strprintf(
          "the charts do not fit one %dx%d lightmap at any density: baked on %d pages of %dx%d "
          "at %.3g texels per unit; raise --resolution for fewer pages",
          as.resolution, as.resolution, attempt.pages, as.resolution, as.resolution, density));
  } else {
    ++report.pack_attempts;
    auto a = pack_at(meshes, density, pack);
    if (!a && a.status().code() == StatusCode::kResourceExhausted && options.max_pages > 1) {
      // Too large for one max_resolution square: several pages.
      a = pack_pages_lowering(meshes, density, pack, options.max_pages, &report.pack_attempts,
                              warnings);
    }
    if (!a) return a.status();
    attempt = std::move(a.value());
  }
  report.pages = attempt.pages;
  report.efficiency = attempt.pack.efficiency;
  return attempt;
}

// 4. Stretch over the laid-out charts (Sander et al. 2001: L2 combines as
// the root of the area-weighted mean of squares).
void measure_stretch(const scene::Scene& scene, const std::vector<MeshCharts>& meshes,
                     UvReport& report) {
  double l2_sq = 0, area = 0;
  for (uint32_t m = 0; m < meshes.size(); ++m) {
    if (meshes[m].charts.empty()) continue;
    const Stretch st = mesh_stretch(scene.meshes[m], meshes[m].charts);
    l2_sq += st.l2 * st.l2 * st.area_3d;
    area += st.area_3d;
    report.stretch_linf = std::max(report.stretch_linf, st.linf);
  }
  if (area > 0) report.stretch_l2 = std::sqrt(l2_sq / area);
}

}  // namespace

Result<GeneratedUvs> generate_lightmap_uvs(const scene::Scene& scene,
                                           const GenerateOptions& options) {
  const SteadyClock::time_point t0 = SteadyClock::now();
  const atlas::AtlasSettings& as = options.atlas;
  if (scene.instances.empty())
    return invalid_argument(
        "scene has no geometry: no mesh instance with triangles to bake (only triangles "
        "are lightmapped, not points or lines)");
  if (as.resolution == 0 && !(std::isfinite(as.texel_density) && as.texel_density > 0))
    return invalid_argument(strprintf(
        "texel_density is %g with resolution 0; set a resolution >= 1 or a finite texel_density "
        "> 0 (texels per world unit)",
        static_cast<double>(as.texel_density)));
  GeneratedUvs out;
  UvReport& report = out.report;
  const SteadyClock::time_point t_charts = SteadyClock::now();
  auto meshes = chart_meshes(scene, options);
  if (!meshes) return meshes.status();
  report.chart_seconds = seconds_since(t_charts);
  const SteadyClock::time_point t_pack = SteadyClock::now();
  double density = 0;
  std::vector<std::string> warnings;
  auto attempt = pack_meshes(meshes.value(), options, density, report, warnings);
  if (!attempt) return attempt.status();
  report.pack_seconds = seconds_since(t_pack);
  // 3. Assembly: new vertices on seams, TEXCOORD_1, placements
  // (generate_assembly.cpp).
  assemble_atlas(scene, meshes.value(), attempt.value(), density, out);
  if (report.meshes == 0) return no_triangles();
  out.atlas.warnings = std::move(warnings);
  measure_stretch(scene, meshes.value(), report);
  measure_layout(out.scene, out.atlas, &report);
  report.total_seconds = seconds_since(t0);
  return out;
}

}  // namespace luxel::uv
