#include "post/lightmapped_gltf.h"

#include <cstring>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "common/atomic_file.h"
#include "scene/gltf_decompress.h"
#include "scene/gltf_document.h"
#include "scene/mesh_build.h"

namespace luxel::pipeline {
namespace {

using nlohmann::json;
using scene::Bytes;
using scene::GltfDocument;

constexpr int kFloat = 5126, kUnsignedShort = 5123, kUnsignedInt = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

Result<std::vector<uint32_t>> read_indices(const GltfDocument& doc, const json& prim,
                                           size_t vertex_count) {
  std::vector<uint32_t> out;
  if (!prim.contains("indices")) {
    out.resize(vertex_count);
    for (size_t i = 0; i < vertex_count; ++i) out[i] = static_cast<uint32_t>(i);
    return out;
  }
  size_t esize = 0;
  auto raw = scene::read_accessor_elements(doc, prim["indices"].get<int>(), &esize);
  if (!raw) return raw.status();
  out.resize(raw.value().size() / esize);
  for (size_t i = 0; i < out.size(); ++i) {
    uint32_t v = 0;
    std::memcpy(&v, raw.value().data() + i * esize, esize);
    out[i] = v;
  }
  return out;
}

// A copy of accessor `index` with `extra` elements appended: element k is
// a copy of element origin[k].
Result<int> grown_accessor(GltfDocument* doc, int index, const std::vector<uint32_t>& origin) {
  size_t esize = 0;
  auto data = scene::read_accessor_elements(*doc, index, &esize);
  if (!data) return data.status();
  Bytes& d = data.value();
  const size_t count = d.size() / esize;
  d.reserve(d.size() + origin.size() * esize);
  for (uint32_t o : origin) {
    if (o >= count)
      return invalid_argument(strprintf("accessors[%d]: vertex %u out of range", index, o));
    d.insert(d.end(), d.begin() + static_cast<long>(o * esize),
             d.begin() + static_cast<long>((o + 1) * esize));
  }
  json a = doc->json["accessors"][static_cast<size_t>(index)];
  a.erase("sparse");
  a["byteOffset"] = 0;
  a["count"] = count + origin.size();
  a["bufferView"] = scene::append_buffer_view(doc, d.data(), d.size(), kArrayBuffer);
  doc->json["accessors"].push_back(a);
  return static_cast<int>(doc->json["accessors"].size()) - 1;
}

// A new VEC2 float accessor over `uv` (2 floats per vertex) with its bounds.
int add_uv_accessor(GltfDocument* doc, const std::vector<float>& uv) {
  float lo[2] = {0, 0}, hi[2] = {0, 0};
  for (size_t k = 0; k < uv.size(); ++k) {
    lo[k % 2] = k < 2 ? uv[k] : std::min(lo[k % 2], uv[k]);
    hi[k % 2] = k < 2 ? uv[k] : std::max(hi[k % 2], uv[k]);
  }
  json a = {{"componentType", kFloat},
            {"type", "VEC2"},
            {"count", uv.size() / 2},
            {"min", {lo[0], lo[1]}},
            {"max", {hi[0], hi[1]}}};
  a["bufferView"] = scene::append_buffer_view(doc, uv.data(), uv.size() * 4, kArrayBuffer);
  doc->json["accessors"].push_back(a);
  return static_cast<int>(doc->json["accessors"].size()) - 1;
}

// Every `texCoord` member anywhere below `node` (textureInfo objects of the
// core material and of every material extension, KHR_texture_transform's
// override included): the UV sets a material reads.
void collect_texcoords(const json& node, std::set<int>* sets) {
  if (node.is_object()) {
    for (const auto& [key, value] : node.items()) {
      if (key == "texCoord" && value.is_number_integer()) sets->insert(value.get<int>());
      collect_texcoords(value, sets);
    }
  } else if (node.is_array()) {
    for (const json& v : node) collect_texcoords(v, sets);
  }
}

// The UV sets the primitive's materials read: its own material and every
// KHR_materials_variants alternative.
std::set<int> material_texcoords(const json& doc, const json& prim) {
  std::set<int> sets;
  auto add = [&](const json& index) {
    if (!index.is_number_integer() || !doc.contains("materials")) return;
    const int m = index.get<int>();
    if (m >= 0 && static_cast<size_t>(m) < doc["materials"].size())
      collect_texcoords(doc["materials"][static_cast<size_t>(m)], &sets);
  };
  if (prim.contains("material")) add(prim["material"]);
  if (prim.contains("extensions") && prim["extensions"].contains("KHR_materials_variants")) {
    const json& v = prim["extensions"]["KHR_materials_variants"];
    if (v.contains("mappings") && v["mappings"].is_array())
      for (const json& mapping : v["mappings"])
        if (mapping.is_object() && mapping.contains("material")) add(mapping["material"]);
  }
  return sets;
}

bool has_attribute(const json& prim, int set) {
  return prim["attributes"].contains("TEXCOORD_" + std::to_string(set));
}

// The TEXCOORD index the lightmap UVs go to. Never a set anything in the
// file uses: the one an earlier write-back recorded (extras.lightmapTexCoord)
// is replaced unless a material reads it; otherwise the first index from 1
// up that the primitive lacks and no material reads. 1 when the file allows
// it: Unity (the second UV set, Mesh.uv2), Godot (UV2) and Unreal (lightmap
// coordinate index 1) all read lightmaps from the second set by default.
int lightmap_target(const json& prim, const std::set<int>& read) {
  if (prim.contains("extras") && prim["extras"].is_object() &&
      prim["extras"].contains("lightmapTexCoord") &&
      prim["extras"]["lightmapTexCoord"].is_number_integer()) {
    const int recorded = prim["extras"]["lightmapTexCoord"].get<int>();
    if (recorded >= 0 && has_attribute(prim, recorded) && !read.count(recorded)) return recorded;
  }
  int set = 1;
  while (has_attribute(prim, set) || read.count(set)) ++set;
  return set;
}

}  // namespace

Result<std::string> lightmapped_glb_bytes(std::string_view source, const std::string& base_dir,
                                          const scene::Scene& scene, const BakeResult& result,
                                          WritebackReport* report) {
  if (!result.uv_layout)
    return invalid_argument(
        "the bake used the file's lightmap UVs; there are no generated UVs to write");
  const GeneratedUvLayout& layout = *result.uv_layout;
  if (layout.meshes.size() != scene.meshes.size())
    return invalid_argument("the generated UVs belong to another scene");
  auto read = scene::read_gltf_document(source, base_dir);
  if (!read) return read.status();
  GltfDocument& doc = read.value();
  // Compressed geometry is written back decoded: the importer read the same
  // decoded vertices (scene/gltf_decompress.h), which the UVs index.
  LUXEL_RETURN_IF_ERROR(scene::decompress_geometry(&doc));
  json& j = doc.json;

  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    const scene::Mesh& mesh = scene.meshes[m];
    const GeneratedUvLayout::MeshUvs& uvs = layout.meshes[m];
    if (uvs.vertex_origin.empty()) continue;
    if (mesh.gltf_index < 0 || !j.contains("meshes") ||
        static_cast<size_t>(mesh.gltf_index) >= j["meshes"].size())
      return invalid_argument(strprintf("mesh '%s' is not in the file", mesh.name.c_str()));
    json& gm = j["meshes"][static_cast<size_t>(mesh.gltf_index)];
    const uint32_t input_vertices = static_cast<uint32_t>(mesh.positions.size());
    // Seam copies (vertices past the input's) by the primitive their origin
    // belongs to, in order: spans are in vertex order.
    std::vector<std::vector<uint32_t>> copies(mesh.primitive_spans.size());
    for (uint32_t w = input_vertices; w < uvs.vertex_origin.size(); ++w) {
      const uint32_t o = uvs.vertex_origin[w];
      const auto it = std::upper_bound(
          mesh.primitive_spans.begin(), mesh.primitive_spans.end(), o,
          [](uint32_t v, const scene::Mesh::PrimitiveSpan& s) { return v < s.first_vertex; });
      if (it != mesh.primitive_spans.begin())
        copies[static_cast<size_t>(it - mesh.primitive_spans.begin()) - 1].push_back(w);
    }
    for (size_t s = 0; s < mesh.primitive_spans.size(); ++s) {
      const scene::Mesh::PrimitiveSpan& span = mesh.primitive_spans[s];
      json& prim = gm["primitives"][static_cast<size_t>(span.primitive)];
      const std::string where =
          strprintf("mesh '%s' primitive %d", mesh.name.c_str(), span.primitive);
      const int mode = prim.value("mode", 4);
      if (mode < 4 || mode > 6) {
        report->warnings.push_back(where + ": not triangles (mode " + std::to_string(mode) +
                                   "); its lightmap UVs were not written");
        continue;
      }
      // Vertices of this primitive: its own (first copies), then the seam
      // copies whose origin lies in its range, in order.
      const uint32_t lo = span.first_vertex, hi = span.first_vertex + span.vertex_count;
      std::vector<uint32_t> appended_origin;  // primitive-local origin of each appended vertex
      std::map<uint32_t, uint32_t> appended_local;
      for (uint32_t w : copies[s]) {
        appended_local[w] = span.vertex_count + static_cast<uint32_t>(appended_origin.size());
        appended_origin.push_back(uvs.vertex_origin[w] - lo);
      }
      auto local = [&](uint32_t w) -> uint32_t {
        if (w < input_vertices) return w >= lo && w < hi ? w - lo : UINT32_MAX;
        const auto it = appended_local.find(w);
        return it == appended_local.end() ? UINT32_MAX : it->second;
      };
      auto indices = read_indices(doc, prim, span.vertex_count);
      if (!indices) return indices.status();
      // Strips and fans are written as the triangle list the importer read
      // (mesh_build.h), so source_triangle positions apply.
      std::vector<uint32_t> idx = scene::detail::to_triangle_list(mode, indices.value());
      prim["mode"] = 4;
      for (uint32_t t = 0; t < span.triangle_count; ++t) {
        const uint32_t st = span.first_triangle + t;
        const uint32_t src = mesh.source_triangle[st];
        if (3 * src + 2 >= idx.size())
          return invalid_argument(where + ": the file's triangles do not match the scene");
        for (uint32_t k = 0; k < 3; ++k) {
          const uint32_t w = uvs.indices[3 * st + k];
          if (w >= uvs.uv1.size() || local(w) == UINT32_MAX)
            return invalid_argument(where +
                                    ": a generated triangle uses another primitive's vertex");
          idx[3 * src + k] = local(w);
        }
      }
      const uint32_t total = span.vertex_count + static_cast<uint32_t>(appended_origin.size());
      const std::set<int> read_sets = material_texcoords(j, prim);
      const int target = lightmap_target(prim, read_sets);
      const std::string target_name = "TEXCOORD_" + std::to_string(target);
      // Every other attribute (and morph target) grows by the seam copies.
      if (!appended_origin.empty()) {
        for (auto& [name, acc] : prim["attributes"].items()) {
          if (name == target_name) continue;
          auto grown = grown_accessor(&doc, acc.get<int>(), appended_origin);
          if (!grown) return grown.status();
          acc = grown.value();
        }
        if (prim.contains("targets")) {
          for (json& morph : prim["targets"]) {
            for (auto& [name, acc] : morph.items()) {
              auto grown = grown_accessor(&doc, acc.get<int>(), appended_origin);
              if (!grown) return grown.status();
              acc = grown.value();
            }
          }
        }
      }
      // The generated UVs into the target set; the sets below it that the
      // primitive lacks are added as zeros (glTF 2.0 §3.7.2.1: TEXCOORD_n
      // indices start at 0 and have no gaps; importers stop at a gap).
      std::vector<float> uv(2 * static_cast<size_t>(total), 0.0f);
      for (uint32_t v = lo; v < hi; ++v) {
        uv[2 * (v - lo)] = uvs.uv1[v].x;
        uv[2 * (v - lo) + 1] = uvs.uv1[v].y;
      }
      for (const auto& [w, l] : appended_local) {
        uv[2 * l] = uvs.uv1[w].x;
        uv[2 * l + 1] = uvs.uv1[w].y;
      }
      prim["attributes"][target_name] = add_uv_accessor(&doc, uv);
      for (int set = 0; set < target; ++set) {
        if (has_attribute(prim, set)) continue;
        prim["attributes"]["TEXCOORD_" + std::to_string(set)] =
            add_uv_accessor(&doc, std::vector<float>(2 * static_cast<size_t>(total), 0.0f));
        ++report->filler_sets;
      }
      if (!prim.contains("extras") || prim["extras"].is_object()) {
        prim["extras"]["lightmapTexCoord"] = target;
      } else {
        report->warnings.push_back(where +
                                   ": extras is not an object; lightmapTexCoord not written");
      }
      if (target != 1)
        report->warnings.push_back(strprintf(
            "%s: TEXCOORD_1 is %s, so the lightmap UVs are in TEXCOORD_%d "
            "(extras.lightmapTexCoord); an engine that reads lightmaps from the second UV set "
            "must be told",
            where.c_str(), read_sets.count(1) ? "read by its material" : "the file's own", target));
      ++report->texcoord_primitives[target];
      // The index list, in the narrowest type that holds it.
      json index_accessor = {{"type", "SCALAR"}, {"count", idx.size()}};
      if (total <= 65535) {
        std::vector<uint16_t> narrow(idx.begin(), idx.end());
        index_accessor["componentType"] = kUnsignedShort;
        index_accessor["bufferView"] =
            scene::append_buffer_view(&doc, narrow.data(), narrow.size() * 2, kElementArrayBuffer);
      } else {
        index_accessor["componentType"] = kUnsignedInt;
        index_accessor["bufferView"] =
            scene::append_buffer_view(&doc, idx.data(), idx.size() * 4, kElementArrayBuffer);
      }
      j["accessors"].push_back(index_accessor);
      prim["indices"] = j["accessors"].size() - 1;
      ++report->primitives;
      report->added_vertices += appended_origin.size();
    }
  }

  // Per node: where its instance(s) sit in the atlas.
  std::map<int, std::vector<size_t>> node_instances;
  for (size_t i = 0; i < scene.instances.size(); ++i)
    if (scene.instances[i].node_index >= 0)
      node_instances[scene.instances[i].node_index].push_back(i);
  for (const auto& [node, list] : node_instances) {
    if (!j.contains("nodes") || static_cast<size_t>(node) >= j["nodes"].size()) continue;
    json& n = j["nodes"][static_cast<size_t>(node)];
    if (n.contains("extras") && !n["extras"].is_object()) {
      report->warnings.push_back(
          strprintf("node %d: extras is not an object; lightmapScaleOffset not written", node));
      continue;
    }
    // Relative to the instance's page; the page is Unity's lightmapIndex.
    auto placed = [&](size_t i) {
      return atlas::page_relative(result.atlas, result.atlas.placements[i]);
    };
    auto so = [&](size_t i) {
      const atlas::InstancePlacement p = placed(i);
      return json::array({p.scale[0], p.scale[1], p.offset[0], p.offset[1]});
    };
    const bool paged = result.atlas.pages > 1;
    if (list.size() == 1) {
      n["extras"]["lightmapScaleOffset"] = so(list[0]);
      if (paged) n["extras"]["lightmapIndex"] = placed(list[0]).page;
    } else {
      json all = json::array(), index = json::array();
      for (size_t i : list) {
        all.push_back(so(i));
        index.push_back(placed(i).page);
      }
      n["extras"]["lightmapScaleOffsets"] = all;
      if (paged) n["extras"]["lightmapIndices"] = index;
    }
    ++report->nodes;
  }
  return scene::write_glb(std::move(doc));
}

Result<WritebackReport> write_lightmapped_glb(const std::string& source_path,
                                              const scene::Scene& scene, const BakeResult& result,
                                              const std::string& out_path) {
  auto bytes = read_whole_file(source_path);
  if (!bytes) return bytes.status();
  WritebackReport report;
  const std::string base_dir = std::filesystem::path(source_path).parent_path().string();
  auto glb = lightmapped_glb_bytes(bytes.value(), base_dir.empty() ? "." : base_dir, scene, result,
                                   &report);
  if (!glb) return glb.status();
  LUXEL_RETURN_IF_ERROR(write_file_atomic(out_path, glb.value()));
  return report;
}

}  // namespace luxel::pipeline
