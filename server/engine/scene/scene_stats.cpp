// See scene_stats.h.
#include "scene/scene_stats.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "common/status.h"
#include "scene/uv_raster.h"

namespace luxel::scene {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Mean linear RGB of a texture (1 when it was not decoded: the factor alone).
double texture_mean(const Texture& t) {
  if (!t.has_pixels()) return 1.0;
  double sum = 0;
  for (size_t i = 0; i < t.texel_count(); ++i) {
    const Vec4 l = t.linear(i);
    sum += static_cast<double>(l.x) + static_cast<double>(l.y) + static_cast<double>(l.z);
  }
  return sum / (3.0 * static_cast<double>(t.texel_count()));
}

// Radiant-exitance-like scale of a material: mean over RGB of emissive factor
// x strength x (mean of the emissive texture).
double emission(const Scene& scene, const Material& m) {
  if (!m.is_emissive()) return 0;
  const Vec3 f = m.emissive_factor;
  double e = (static_cast<double>(f.x) + static_cast<double>(f.y) + static_cast<double>(f.z)) /
             3.0 * static_cast<double>(m.emissive_strength);
  const int t = m.emissive_texture.texture;
  if (t >= 0 && static_cast<size_t>(t) < scene.textures.size())
    e *= texture_mean(scene.textures[static_cast<size_t>(t)]);
  return e;
}

void add_mesh(const Mesh& m, UvRaster* raster) {
  for (size_t t = 0; t < m.triangle_count(); ++t)
    raster->add(m.uv1[m.indices[3 * t]], m.uv1[m.indices[3 * t + 1]], m.uv1[m.indices[3 * t + 2]]);
}

}  // namespace

SceneStats compute_stats(const Scene& scene, int coverage_resolution) {
  SceneStats s;
  s.meshes = scene.meshes.size();
  s.instances = scene.instances.size();
  s.materials = scene.materials.size();
  s.textures = scene.textures.size();
  for (const auto& t : scene.textures) s.texture_bytes += t.pixel_bytes();
  for (const auto& l : scene.lights) {
    if (l.type == LightType::kPoint) ++s.point_lights;
    if (l.type == LightType::kSpot) ++s.spot_lights;
    if (l.type == LightType::kDirectional) ++s.directional_lights;
  }
  s.degenerate_triangles_dropped = scene.import_stats.degenerate_triangles_dropped;
  s.skipped_primitives = scene.import_stats.skipped_primitives;

  std::vector<double> emission_of(scene.materials.size());
  for (size_t i = 0; i < scene.materials.size(); ++i)
    emission_of[i] = emission(scene, scene.materials[i]);
  auto material_at = [&](const Mesh& m, size_t t) -> const Material* {
    const int id = t < m.triangle_material.size() ? m.triangle_material[t] : -1;
    return id >= 0 && static_cast<size_t>(id) < scene.materials.size()
               ? &scene.materials[static_cast<size_t>(id)]
               : nullptr;
  };

  for (const auto& m : scene.meshes) s.mesh_triangles += m.triangle_count();
  for (const auto& inst : scene.instances) {
    if (inst.mesh < 0 || static_cast<size_t>(inst.mesh) >= scene.meshes.size()) continue;
    const Mesh& m = scene.meshes[static_cast<size_t>(inst.mesh)];
    s.world_triangles += m.triangle_count();
    for (const Vec3& p : m.positions)
      s.world_bounds.extend(transform_point(inst.object_to_world, p));
    for (size_t t = 0; t < m.triangle_count(); ++t) {
      const Material* mat = material_at(m, t);
      if (mat == nullptr) continue;
      if (mat->alpha_mode == AlphaMode::kMask) ++s.alpha_masked_triangles;
      const double e = emission_of[static_cast<size_t>(mat - scene.materials.data())];
      if (e > 0) {
        ++s.emissive_triangles;
        s.emissive_power +=
            kPi * e *
            transformed_triangle_area(inst.object_to_world, m.positions[m.indices[3 * t]],
                                      m.positions[m.indices[3 * t + 1]],
                                      m.positions[m.indices[3 * t + 2]]);
      }
    }
  }

  const int res = std::max(1, coverage_resolution);
  s.coverage_resolution = res;
  // Per texel: whether one mesh covered it twice, and whether another mesh
  // covered it too. Meshes laid out in their own unit square (instanced
  // meshes, per-mesh layouts) overlap each other by design until the atlas
  // packer places them; overlap inside one mesh is a UV error.
  UvRaster raster(res);
  const size_t texels = static_cast<size_t>(res) * static_cast<size_t>(res);
  std::vector<int32_t> owner(texels, -1);
  std::vector<uint8_t> flags(texels, 0);  // 1: covered, 2: self-overlap, 4: cross-mesh
  for (size_t mi = 0; mi < scene.meshes.size(); ++mi) {
    const Mesh& m = scene.meshes[mi];
    if (m.uv1.size() != m.positions.size()) continue;
    add_mesh(m, &raster);
    raster.resolve([&](size_t i, int32_t count) {
      if (count > 1) flags[i] |= 2;
      if (owner[i] >= 0 && owner[i] != static_cast<int32_t>(mi)) flags[i] |= 4;
      owner[i] = static_cast<int32_t>(mi);
      flags[i] |= 1;
    });
  }
  size_t covered = 0;
  for (uint8_t f : flags) {
    covered += (f & 1) != 0;
    s.lightmap_overlap_texels += (f & 2) != 0;
    s.lightmap_shared_texels += (f & 4) != 0;
  }
  s.lightmap_coverage = static_cast<double>(covered) / static_cast<double>(texels);
  return s;
}

std::vector<UvOverlap> find_uv_overlaps(const Scene& scene, int resolution) {
  std::vector<UvOverlap> out;
  UvRaster raster(std::max(1, resolution));
  for (size_t mi = 0; mi < scene.meshes.size(); ++mi) {
    const Mesh& m = scene.meshes[mi];
    if (m.uv1.size() != m.positions.size()) continue;
    add_mesh(m, &raster);
    size_t overlapping = 0;
    raster.resolve([&](size_t, int32_t count) { overlapping += count > 1; });
    if (overlapping > 0) out.push_back({static_cast<int>(mi), overlapping});
  }
  return out;
}

std::string format_stats(const SceneStats& s) {
  std::ostringstream o;
  o << "meshes:            " << s.meshes << " (" << s.instances << " instances)\n"
    << "triangles:         " << s.mesh_triangles << " unique, " << s.world_triangles
    << " after instancing\n"
    << "materials:         " << s.materials << " (" << s.alpha_masked_triangles
    << " alpha-masked triangles)\n"
    << "textures:          " << s.textures << " ("
    << strprintf("%.1f", static_cast<double>(s.texture_bytes) / (1 << 20)) << " MiB decoded)\n"
    << "punctual lights:   " << s.point_lights << " point, " << s.spot_lights << " spot, "
    << s.directional_lights << " directional\n"
    << "emissive:          " << s.emissive_triangles << " triangles, power "
    << strprintf("%.6g", s.emissive_power) << " (emissive units x m^2)\n";
  if (s.world_bounds.empty()) {
    o << "bounds:            empty\n";
  } else {
    const auto& b = s.world_bounds;
    o << strprintf("bounds:            (%g, %g, %g) .. (%g, %g, %g)\n", static_cast<double>(b.lo.x),
                   static_cast<double>(b.lo.y), static_cast<double>(b.lo.z),
                   static_cast<double>(b.hi.x), static_cast<double>(b.hi.y),
                   static_cast<double>(b.hi.z));
  }
  o << strprintf(
           "lightmap UVs:      %.2f%% of %d^2 texels covered, %zu overlap within a mesh, %zu "
           "shared by several meshes\n",
           100.0 * s.lightmap_coverage, s.coverage_resolution, s.lightmap_overlap_texels,
           s.lightmap_shared_texels)
    << "import:            " << s.degenerate_triangles_dropped << " degenerate triangles dropped, "
    << s.skipped_primitives << " non-triangle primitives skipped\n";
  return o.str();
}

}  // namespace luxel::scene
