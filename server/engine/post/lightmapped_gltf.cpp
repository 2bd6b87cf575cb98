#include "post/lightmapped_gltf.h"

#include <openssl/evp.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "common/atomic_file.h"
#include "common/uri.h"
#include "scene/mesh_build.h"

namespace luxel::pipeline {
namespace {

using nlohmann::json;
using Bytes = std::vector<uint8_t>;

constexpr uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr uint32_t kChunkJson = 0x4E4F534A;
constexpr uint32_t kChunkBin = 0x004E4942;
constexpr int kFloat = 5126, kUnsignedShort = 5123, kUnsignedInt = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

uint32_t read_u32(std::string_view s, size_t at) {
  uint32_t v = 0;
  std::memcpy(&v, s.data() + at, 4);
  return v;
}

// The JSON and the GLB binary chunk (empty for a .gltf).
Status parse_container(std::string_view bytes, json* doc, Bytes* bin) {
  std::string_view text = bytes;
  if (bytes.size() >= 12 && read_u32(bytes, 0) == kGlbMagic) {
    const size_t length = std::min<size_t>(read_u32(bytes, 8), bytes.size());
    size_t at = 12;
    text = {};
    while (at + 8 <= length) {
      const uint32_t chunk_length = read_u32(bytes, at), type = read_u32(bytes, at + 4);
      if (at + 8 + chunk_length > length) return data_loss("GLB chunk runs past the file's end");
      const std::string_view chunk = bytes.substr(at + 8, chunk_length);
      if (type == kChunkJson && text.empty()) text = chunk;
      if (type == kChunkBin && bin->empty()) bin->assign(chunk.begin(), chunk.end());
      at += 8 + chunk_length;
    }
    if (text.empty()) return data_loss("GLB has no JSON chunk");
  }
  *doc = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (doc->is_discarded() || !doc->is_object()) return data_loss("the glTF JSON does not parse");
  return Status::ok();
}

Result<Bytes> decode_base64(std::string_view text) {
  Bytes out(3 * ((text.size() + 3) / 4) + 3);
  const int n = EVP_DecodeBlock(out.data(), reinterpret_cast<const unsigned char*>(text.data()),
                                static_cast<int>(text.size()));
  if (n < 0) return data_loss("malformed base64 in a data URI");
  size_t pad = 0;
  for (size_t i = text.size(); i > 0 && text[i - 1] == '='; --i) ++pad;
  out.resize(static_cast<size_t>(n) - std::min<size_t>(pad, static_cast<size_t>(n)));
  return out;
}

// The bytes a buffer or image URI names.
Result<Bytes> read_uri(const std::string& uri, const std::string& base_dir,
                       const std::string& what) {
  if (uri.rfind("data:", 0) == 0) {
    const size_t comma = uri.find(',');
    if (comma == std::string::npos || uri.find(";base64", 0) > comma)
      return data_loss(what + ": malformed data URI (expected data:...;base64,...)");
    auto d = decode_base64(std::string_view(uri).substr(comma + 1));
    if (!d) return data_loss(what + ": " + d.status().message());
    return d;
  }
  if (base_dir.empty())
    return invalid_argument(what + ": external file '" + uri + "' not available");
  auto name = percent_decode_uri(uri);
  if (!name) return invalid_argument(what + ": " + name.status().message());
  std::ifstream in(std::filesystem::path(base_dir) / name.value(), std::ios::binary);
  if (!in) return not_found(what + ": cannot read '" + name.value() + "'");
  std::ostringstream ss;
  ss << in.rdbuf();
  const std::string s = ss.str();
  return Bytes(s.begin(), s.end());
}

void align(Bytes* bin) {
  while (bin->size() % 4 != 0) bin->push_back(0);
}

// Appends data as a new bufferView of buffer 0; returns its index.
int add_view(json& doc, Bytes* bin, const void* data, size_t bytes, int target) {
  align(bin);
  json view = {{"buffer", 0}, {"byteOffset", bin->size()}, {"byteLength", bytes}};
  if (target) view["target"] = target;
  const auto* p = static_cast<const uint8_t*>(data);
  bin->insert(bin->end(), p, p + bytes);
  doc["bufferViews"].push_back(view);
  return static_cast<int>(doc["bufferViews"].size()) - 1;
}

// Every buffer (GLB chunk, data URI, external file) merged into buffer 0,
// and external images embedded, so the result is one self-contained GLB.
Status merge_buffers(json& doc, const Bytes& glb_bin, const std::string& base_dir, Bytes* bin) {
  std::vector<size_t> base;
  if (doc.contains("buffers")) {
    for (size_t b = 0; b < doc["buffers"].size(); ++b) {
      const json& buffer = doc["buffers"][b];
      align(bin);
      base.push_back(bin->size());
      const std::string what = strprintf("buffers[%zu]", b);
      if (buffer.contains("uri") && buffer["uri"].is_string()) {
        auto data = read_uri(buffer["uri"].get<std::string>(), base_dir, what);
        if (!data) return data.status();
        bin->insert(bin->end(), data.value().begin(), data.value().end());
      } else if (b == 0) {
        bin->insert(bin->end(), glb_bin.begin(), glb_bin.end());
      }
      // (An unused buffer without data is valid glTF; nothing refers to it.)
    }
  }
  if (doc.contains("bufferViews")) {
    for (json& view : doc["bufferViews"]) {
      const size_t b = view.value("buffer", 0);
      if (b >= base.size())
        return invalid_argument("a bufferView names a buffer that does not exist");
      view["buffer"] = 0;
      view["byteOffset"] = view.value("byteOffset", size_t{0}) + base[b];
    }
  }
  if (doc.contains("images")) {
    for (size_t i = 0; i < doc["images"].size(); ++i) {
      json& image = doc["images"][i];
      if (!image.contains("uri") || !image["uri"].is_string()) continue;
      const std::string uri = image["uri"].get<std::string>();
      if (uri.rfind("data:", 0) == 0) continue;  // self-contained already
      auto data = read_uri(uri, base_dir, strprintf("images[%zu]", i));
      if (!data) return data.status();
      const std::string ext = std::filesystem::path(uri).extension().string();
      image["mimeType"] = (ext == ".jpg" || ext == ".jpeg") ? "image/jpeg" : "image/png";
      image.erase("uri");
      image["bufferView"] = add_view(doc, bin, data.value().data(), data.value().size(), 0);
    }
  }
  return Status::ok();
}

int components(const std::string& type) {
  if (type == "SCALAR") return 1;
  if (type == "VEC2") return 2;
  if (type == "VEC3") return 3;
  if (type == "VEC4" || type == "MAT2") return 4;
  if (type == "MAT3") return 9;
  if (type == "MAT4") return 16;
  return 0;
}

int component_bytes(int component_type) {
  switch (component_type) {
    case 5120:
    case 5121:
      return 1;
    case 5122:
    case 5123:
      return 2;
    case 5125:
    case 5126:
      return 4;
    default:
      return 0;
  }
}

// An accessor's elements, tightly packed (stride removed, sparse applied,
// zeros without a bufferView).
Result<Bytes> read_elements(const json& doc, const Bytes& bin, int index, size_t* element_size) {
  const std::string what = strprintf("accessors[%d]", index);
  if (index < 0 || !doc.contains("accessors") ||
      static_cast<size_t>(index) >= doc["accessors"].size())
    return invalid_argument(what + " does not exist");
  const json& a = doc["accessors"][static_cast<size_t>(index)];
  const size_t count = a.value("count", size_t{0});
  const size_t esize = static_cast<size_t>(component_bytes(a.value("componentType", 0)) *
                                           components(a.value("type", std::string())));
  if (esize == 0) return invalid_argument(what + ": unknown componentType or type");
  *element_size = esize;
  Bytes out(count * esize, 0);
  auto copy_from_view = [&](int view_index, size_t offset, size_t n, size_t elem,
                            auto&& sink) -> Status {
    if (view_index < 0 || static_cast<size_t>(view_index) >= doc["bufferViews"].size())
      return invalid_argument(what + ": bufferView does not exist");
    const json& v = doc["bufferViews"][static_cast<size_t>(view_index)];
    const size_t stride = v.value("byteStride", elem) ? v.value("byteStride", elem) : elem;
    const size_t start = v.value("byteOffset", size_t{0}) + offset;
    if (n > 0 && start + (n - 1) * stride + elem > bin.size())
      return invalid_argument(what + ": data runs past its buffer");
    for (size_t i = 0; i < n; ++i) sink(i, bin.data() + start + i * stride);
    return Status::ok();
  };
  if (a.contains("bufferView")) {
    LUXEL_RETURN_IF_ERROR(copy_from_view(
        a["bufferView"].get<int>(), a.value("byteOffset", size_t{0}), count, esize,
        [&](size_t i, const uint8_t* p) { std::memcpy(out.data() + i * esize, p, esize); }));
  }
  if (a.contains("sparse")) {
    const json& sp = a["sparse"];
    const size_t n = sp.value("count", size_t{0});
    const json& ix = sp["indices"];
    const int ictype = ix.value("componentType", 0);
    const size_t isize = static_cast<size_t>(component_bytes(ictype));
    std::vector<size_t> targets(n);
    LUXEL_RETURN_IF_ERROR(copy_from_view(ix.value("bufferView", -1),
                                         ix.value("byteOffset", size_t{0}), n, isize,
                                         [&](size_t i, const uint8_t* p) {
                                           uint32_t t = 0;
                                           std::memcpy(&t, p, isize);
                                           targets[i] = t;
                                         }));
    for (size_t t : targets)
      if (t >= count) return invalid_argument(what + ": sparse index out of range");
    const json& vals = sp["values"];
    LUXEL_RETURN_IF_ERROR(copy_from_view(vals.value("bufferView", -1),
                                         vals.value("byteOffset", size_t{0}), n, esize,
                                         [&](size_t i, const uint8_t* p) {
                                           std::memcpy(out.data() + targets[i] * esize, p, esize);
                                         }));
  }
  return out;
}

Result<std::vector<uint32_t>> read_indices(const json& doc, const Bytes& bin, const json& prim,
                                           size_t vertex_count) {
  std::vector<uint32_t> out;
  if (!prim.contains("indices")) {
    out.resize(vertex_count);
    for (size_t i = 0; i < vertex_count; ++i) out[i] = static_cast<uint32_t>(i);
    return out;
  }
  size_t esize = 0;
  auto raw = read_elements(doc, bin, prim["indices"].get<int>(), &esize);
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
Result<int> grown_accessor(json& doc, Bytes* bin, int index, const std::vector<uint32_t>& origin) {
  size_t esize = 0;
  auto data = read_elements(doc, *bin, index, &esize);
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
  json a = doc["accessors"][static_cast<size_t>(index)];
  a.erase("sparse");
  a["byteOffset"] = 0;
  a["count"] = count + origin.size();
  a["bufferView"] = add_view(doc, bin, d.data(), d.size(), kArrayBuffer);
  doc["accessors"].push_back(a);
  return static_cast<int>(doc["accessors"].size()) - 1;
}

}  // namespace

Result<std::string> lightmapped_glb_bytes(std::string_view source, const std::string& base_dir,
                                          const scene::Scene& scene, const BakeResult& result,
                                          WritebackReport* report) {
  if (!result.uv_layout)
    return invalid_argument(
        "the bake used the file's TEXCOORD_1; there are no generated UVs to write");
  const GeneratedUvLayout& layout = *result.uv_layout;
  if (layout.meshes.size() != scene.meshes.size())
    return invalid_argument("the generated UVs belong to another scene");
  json doc;
  Bytes glb_bin, bin;
  LUXEL_RETURN_IF_ERROR(parse_container(source, &doc, &glb_bin));
  LUXEL_RETURN_IF_ERROR(merge_buffers(doc, glb_bin, base_dir, &bin));
  if (!doc.contains("accessors")) doc["accessors"] = json::array();
  if (!doc.contains("bufferViews")) doc["bufferViews"] = json::array();

  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    const scene::Mesh& mesh = scene.meshes[m];
    const GeneratedUvLayout::MeshUvs& uvs = layout.meshes[m];
    if (uvs.vertex_origin.empty()) continue;
    if (mesh.gltf_index < 0 || !doc.contains("meshes") ||
        static_cast<size_t>(mesh.gltf_index) >= doc["meshes"].size())
      return invalid_argument(strprintf("mesh '%s' is not in the file", mesh.name.c_str()));
    json& gm = doc["meshes"][static_cast<size_t>(mesh.gltf_index)];
    const uint32_t input_vertices = static_cast<uint32_t>(mesh.positions.size());
    for (const scene::Mesh::PrimitiveSpan& span : mesh.primitive_spans) {
      json& prim = gm["primitives"][static_cast<size_t>(span.primitive)];
      const std::string where =
          strprintf("mesh '%s' primitive %d", mesh.name.c_str(), span.primitive);
      const int mode = prim.value("mode", 4);
      if (mode < 4 || mode > 6 ||
          (prim.contains("extensions") &&
           prim["extensions"].contains("KHR_draco_mesh_compression"))) {
        report->warnings.push_back(where + ": not triangles (mode " + std::to_string(mode) +
                                   ") or Draco-compressed; its TEXCOORD_1 was not written");
        continue;
      }
      // Vertices of this primitive: its own (first copies), then the seam
      // copies whose origin lies in its range, in order.
      const uint32_t lo = span.first_vertex, hi = span.first_vertex + span.vertex_count;
      std::vector<uint32_t> appended_origin;  // primitive-local origin of each appended vertex
      std::vector<uint32_t> local(uvs.uv1.size(), UINT32_MAX);
      for (uint32_t v = lo; v < hi; ++v) local[v] = v - lo;
      for (uint32_t w = input_vertices; w < uvs.vertex_origin.size(); ++w) {
        const uint32_t o = uvs.vertex_origin[w];
        if (o < lo || o >= hi) continue;
        local[w] = span.vertex_count + static_cast<uint32_t>(appended_origin.size());
        appended_origin.push_back(o - lo);
      }
      auto indices = read_indices(doc, bin, prim, span.vertex_count);
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
        for (uint32_t j = 0; j < 3; ++j) {
          const uint32_t w = uvs.indices[3 * st + j];
          if (w >= local.size() || local[w] == UINT32_MAX)
            return invalid_argument(where +
                                    ": a generated triangle uses another primitive's vertex");
          idx[3 * src + j] = local[w];
        }
      }
      const uint32_t total = span.vertex_count + static_cast<uint32_t>(appended_origin.size());
      // TEXCOORD_1: the generated UVs.
      std::vector<float> uv(2 * static_cast<size_t>(total), 0.0f);
      float lo_uv[2] = {INFINITY, INFINITY}, hi_uv[2] = {-INFINITY, -INFINITY};
      for (uint32_t w = 0; w < uvs.uv1.size(); ++w) {
        if (local[w] == UINT32_MAX) continue;
        uv[2 * local[w]] = uvs.uv1[w].x;
        uv[2 * local[w] + 1] = uvs.uv1[w].y;
      }
      for (uint32_t k = 0; k < total; ++k)
        for (int c = 0; c < 2; ++c) {
          lo_uv[c] = std::min(lo_uv[c], uv[2 * k + static_cast<size_t>(c)]);
          hi_uv[c] = std::max(hi_uv[c], uv[2 * k + static_cast<size_t>(c)]);
        }
      // Every other attribute (and morph target) grows by the seam copies.
      if (!appended_origin.empty()) {
        for (auto& [name, acc] : prim["attributes"].items()) {
          if (name == "TEXCOORD_1") continue;
          auto grown = grown_accessor(doc, &bin, acc.get<int>(), appended_origin);
          if (!grown) return grown.status();
          acc = grown.value();
        }
        if (prim.contains("targets")) {
          for (json& target : prim["targets"]) {
            for (auto& [name, acc] : target.items()) {
              auto grown = grown_accessor(doc, &bin, acc.get<int>(), appended_origin);
              if (!grown) return grown.status();
              acc = grown.value();
            }
          }
        }
      }
      json uv_accessor = {{"componentType", kFloat},
                          {"type", "VEC2"},
                          {"count", total},
                          {"min", {lo_uv[0], lo_uv[1]}},
                          {"max", {hi_uv[0], hi_uv[1]}}};
      uv_accessor["bufferView"] = add_view(doc, &bin, uv.data(), uv.size() * 4, kArrayBuffer);
      doc["accessors"].push_back(uv_accessor);
      prim["attributes"]["TEXCOORD_1"] = doc["accessors"].size() - 1;
      // The index list, in the narrowest type that holds it.
      json index_accessor = {{"type", "SCALAR"}, {"count", idx.size()}};
      if (total <= 65535) {
        std::vector<uint16_t> narrow(idx.begin(), idx.end());
        index_accessor["componentType"] = kUnsignedShort;
        index_accessor["bufferView"] =
            add_view(doc, &bin, narrow.data(), narrow.size() * 2, kElementArrayBuffer);
      } else {
        index_accessor["componentType"] = kUnsignedInt;
        index_accessor["bufferView"] =
            add_view(doc, &bin, idx.data(), idx.size() * 4, kElementArrayBuffer);
      }
      doc["accessors"].push_back(index_accessor);
      prim["indices"] = doc["accessors"].size() - 1;
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
    if (!doc.contains("nodes") || static_cast<size_t>(node) >= doc["nodes"].size()) continue;
    json& n = doc["nodes"][static_cast<size_t>(node)];
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

  // One buffer: the merged binary chunk.
  align(&bin);
  doc["buffers"] = json::array({json{{"byteLength", bin.size()}}});
  std::string text = doc.dump();
  while (text.size() % 4 != 0) text.push_back(' ');
  std::string out;
  auto put = [&](uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
  const uint32_t total = static_cast<uint32_t>(12 + 8 + text.size() + 8 + bin.size());
  put(kGlbMagic);
  put(2);
  put(total);
  put(static_cast<uint32_t>(text.size()));
  put(kChunkJson);
  out += text;
  put(static_cast<uint32_t>(bin.size()));
  put(kChunkBin);
  out.append(reinterpret_cast<const char*>(bin.data()), bin.size());
  return out;
}

Result<WritebackReport> write_lightmapped_glb(const std::string& source_path,
                                              const scene::Scene& scene, const BakeResult& result,
                                              const std::string& out_path) {
  std::ifstream in(source_path, std::ios::binary);
  if (!in) return not_found("cannot read '" + source_path + "'");
  std::ostringstream ss;
  ss << in.rdbuf();
  const std::string bytes = ss.str();
  WritebackReport report;
  const std::string base_dir = std::filesystem::path(source_path).parent_path().string();
  auto glb =
      lightmapped_glb_bytes(bytes, base_dir.empty() ? "." : base_dir, scene, result, &report);
  if (!glb) return glb.status();
  LUXEL_RETURN_IF_ERROR(write_file_atomic(out_path, glb.value()));
  return report;
}

}  // namespace luxel::pipeline
