// Step 3 of generate_lightmap_uvs (generate.cpp): the packed charts become
// the scene's lightmap UVs (TEXCOORD_1, new vertices on chart seams) and the
// atlas's instance placements.
#include <string>
#include <vector>

#include "uv/generate_layout.h"

namespace luxel::uv {
namespace {

// Appends a copy of input vertex v with lightmap UV `uv`; returns its index.
uint32_t copy_vertex(const scene::Mesh& in, uint32_t v, Vec2 uv, scene::Mesh& mesh,
                     std::vector<uint32_t>& origin) {
  const uint32_t copy = static_cast<uint32_t>(mesh.positions.size());
  origin.push_back(v);
  mesh.positions.push_back(in.positions[v]);
  mesh.normals.push_back(in.normals[v]);
  mesh.uv0.push_back(in.uv0[v]);
  if (!in.tangents.empty()) mesh.tangents.push_back(in.tangents[v]);
  mesh.file_uv1.push_back(in.material_uvs(1)[v]);
  mesh.uv1.push_back(uv);
  return copy;
}

// Chart vertex -> mesh vertex, splitting a vertex already given a UV;
// chart_uv(chart, uv) is the chart point's lightmap UV.
template <typename ChartUv>
void assemble_mesh(const scene::Scene& scene, const MeshCharts& mc, uint32_t m, ChartUv&& chart_uv,
                   GeneratedUvs& out) {
  const scene::Mesh& in = scene.meshes[m];
  scene::Mesh& mesh = out.scene.meshes[m];
  std::vector<uint32_t>& origin = out.vertex_origin[m];
  origin.resize(in.positions.size());
  for (uint32_t v = 0; v < origin.size(); ++v) origin[v] = v;
  std::vector<bool> assigned(in.positions.size(), false);
  // Material textures on texCoord 1 keep reading the file's TEXCOORD_1
  // (zeros where the file has none, as before generation).
  mesh.file_uv1 = in.material_uvs(1);
  mesh.uv1.assign(in.positions.size(), Vec2{0, 0});
  mesh.has_lightmap_uvs = true;
  std::vector<bool> placed(in.triangle_count(), false);
  for (uint32_t c = 0; c < mc.charts.size(); ++c) {
    const Chart& chart = mc.charts[c];
    std::vector<uint32_t> target(chart.vertices.size());
    for (size_t k = 0; k < chart.vertices.size(); ++k) {
      const uint32_t v = chart.vertices[k];
      const Vec2 uv = chart_uv(c, chart.uv[k]);
      if (!assigned[v]) {
        assigned[v] = true;
        mesh.uv1[v] = uv;
        target[k] = v;
        continue;
      }
      target[k] = copy_vertex(in, v, uv, mesh, origin);
      ++out.report.seam_vertices;
    }
    for (size_t k = 0; k < chart.triangles.size(); ++k) {
      const uint32_t t = chart.triangles[k];
      placed[t] = true;
      for (int j = 0; j < 3; ++j)
        mesh.indices[3 * t + static_cast<size_t>(j)] =
            target[chart.indices[3 * k + static_cast<size_t>(j)]];
    }
  }
  // A triangle in no chart (degenerate) collapses onto one UV point, so it
  // covers no texel: a point of the first chart, which every placement of
  // the mesh keeps inside the atlas.
  const Vec2 anchor = chart_uv(0, mc.charts[0].uv[0]);
  for (uint32_t t = 0; t < placed.size(); ++t) {
    if (placed[t]) continue;
    ++out.report.unplaced_triangles;
    for (int j = 0; j < 3; ++j) {
      const uint32_t v = in.indices[3 * t + static_cast<size_t>(j)];
      mesh.indices[3 * t + static_cast<size_t>(j)] = copy_vertex(in, v, anchor, mesh, origin);
    }
  }
  ++out.report.meshes;
  out.report.charts += mc.charts.size();
  out.report.triangles += in.triangle_count();
}

}  // namespace

// Where the packer puts a shape point (bitimage_packer.h:
// atlas_texel(p) = rotate(p, rotation) + offset), in double.
DPoint placed_point(double x, double y, const ShapePlacement& s) {
  double rx = x, ry = y;
  switch (s.rotation & 3) {
    case 1:
      rx = -y, ry = x;
      break;
    case 2:
      rx = -x, ry = -y;
      break;
    case 3:
      rx = y, ry = -x;
      break;
    default:
      break;
  }
  return {rx + s.offset[0], ry + s.offset[1]};
}

void assemble_atlas(const scene::Scene& scene, const std::vector<MeshCharts>& meshes,
                    const PackAttempt& attempt, double density, GeneratedUvs& out) {
  out.scene = scene;
  out.vertex_origin.resize(scene.meshes.size());
  atlas::Atlas& at = out.atlas;
  at.mode = atlas::AtlasMode::kGenerated;
  // Pages are stacked from the top in one image of pages x page height:
  // the bake sees one lightmap; the outputs cut it into pages again.
  at.width = attempt.pack.width;
  at.height = attempt.pack.height * attempt.pages;
  at.pages = attempt.pages;
  at.texels_per_unit = density;
  at.placements.resize(scene.instances.size());
  for (uint32_t i = 0; i < scene.instances.size(); ++i) at.placements[i].instance = i;
  const double aw = at.width, ah = at.height;

  // Shape index ranges per mesh in attempt.sources order.
  std::vector<std::vector<size_t>> shape_of_chart(meshes.size());
  std::vector<std::vector<size_t>> shape_of_instance(meshes.size());
  for (size_t s = 0; s < attempt.sources.size(); ++s) {
    const ShapeSource& src = attempt.sources[s];
    if (src.instance < 0) {
      auto& v = shape_of_chart[src.mesh];
      if (v.size() <= src.chart) v.resize(src.chart + 1);
      v[src.chart] = s;
    } else {
      shape_of_instance[src.mesh].push_back(s);
    }
  }

  // A shape's placement in the stacked image.
  const double page_height = attempt.pack.height;
  auto stacked = [&](DPoint p, size_t shape) {
    return DPoint{p.x, p.y + page_height * attempt.page[shape]};
  };

  for (uint32_t m = 0; m < meshes.size(); ++m) {
    const MeshCharts& mc = meshes[m];
    if (mc.instances.empty()) continue;
    if (mc.charts.empty()) {
      // Nothing but degenerate triangles: every UV collapses onto the atlas
      // corner, so the file's TEXCOORD_1 (if any) cannot cover texels that
      // charts own; material textures keep reading it.
      const scene::Mesh& in = scene.meshes[m];
      scene::Mesh& mesh = out.scene.meshes[m];
      mesh.file_uv1 = in.material_uvs(1);
      mesh.uv1.assign(in.positions.size(), Vec2{0, 0});
      mesh.has_lightmap_uvs = true;
      std::vector<uint32_t>& origin = out.vertex_origin[m];
      origin.resize(in.positions.size());
      for (uint32_t v = 0; v < origin.size(); ++v) origin[v] = v;
      out.report.unplaced_triangles += in.triangle_count();
      out.report.triangles += in.triangle_count();
      continue;
    }
    if (mc.instances.size() == 1) {
      // Atlas UVs directly.
      assemble_mesh(
          scene, mc, m,
          [&](uint32_t c, Vec2 uv) {
            const double k = density * mc.chart_scale[c];
            const size_t shape = shape_of_chart[m][c];
            const DPoint p =
                stacked(placed_point(uv.x * k, uv.y * k, attempt.pack.placements[shape]), shape);
            return Vec2{static_cast<float>(p.x / aw), static_cast<float>(p.y / ah)};
          },
          out);
      atlas::InstancePlacement& p = at.placements[mc.instances[0]];
      // Its page (a page holds whole instances).
      p.page = attempt.page[shape_of_chart[m][0]];
      p.rect[1] = static_cast<int>(page_height) * p.page;
      p.rect[2] = at.width;
      p.rect[3] = static_cast<int>(page_height);
      continue;
    }
    const MeshLayout& layout = attempt.layouts[m];
    const double lw = layout.width, lh = layout.height;
    assemble_mesh(
        scene, mc, m,
        [&](uint32_t c, Vec2 uv) {
          const DPoint p =
              placed_point(uv.x * layout.scale, uv.y * layout.scale, layout.placements[c]);
          return Vec2{static_cast<float>(p.x / lw), static_cast<float>(p.y / lh)};
        },
        out);
    for (size_t k = 0; k < mc.instances.size(); ++k) {
      const size_t shape = shape_of_instance[m][k];
      const ShapePlacement& sp = attempt.pack.placements[shape];
      const double grow = mc.grow(k);
      atlas::InstancePlacement& p = at.placements[mc.instances[k]];
      // atlas texel = layout texel * grow + offset (no turn: allow_rotation
      // was false), so atlas_uv = uv1 * (l * grow / a) + offset / a.
      const DPoint origin = stacked(placed_point(0, 0, sp), shape);
      p.page = attempt.page[shape];
      p.scale[0] = static_cast<float>(lw * grow / aw);
      p.scale[1] = static_cast<float>(lh * grow / ah);
      p.offset[0] = static_cast<float>(origin.x / aw);
      p.offset[1] = static_cast<float>(origin.y / ah);
      // The texels the instance's conservative mask covers.
      for (int axis = 0; axis < 2; ++axis) {
        p.rect[axis] = sp.mask_origin[axis];
        p.rect[2 + axis] = sp.mask_size[axis];
      }
      p.rect[1] += static_cast<int>(page_height) * p.page;
    }
  }
}

}  // namespace luxel::uv
