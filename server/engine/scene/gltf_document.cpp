#include "scene/gltf_document.h"

#include <openssl/evp.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "common/uri.h"

namespace luxel::scene {
namespace {

using nlohmann::json;

constexpr uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr uint32_t kChunkJson = 0x4E4F534A;
constexpr uint32_t kChunkBin = 0x004E4942;

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

bool is_meshopt_fallback(const json& buffer) {
  if (!buffer.contains("extensions") || !buffer["extensions"].is_object()) return false;
  const json& e = buffer["extensions"];
  if (!e.contains("EXT_meshopt_compression") || !e["EXT_meshopt_compression"].is_object())
    return false;
  const json& m = e["EXT_meshopt_compression"];
  return m.contains("fallback") && m["fallback"].is_boolean() && m["fallback"].get<bool>();
}

void align(Bytes* bin) {
  while (bin->size() % 4 != 0) bin->push_back(0);
}

// Every buffer merged into buffer 0, external images embedded.
Status merge_buffers(GltfDocument* d, const Bytes& glb_bin, const std::string& base_dir) {
  json& doc = d->json;
  Bytes* bin = &d->bin;
  std::vector<size_t> base;
  std::vector<bool> fallback;
  if (doc.contains("buffers")) {
    for (size_t b = 0; b < doc["buffers"].size(); ++b) {
      const json& buffer = doc["buffers"][b];
      align(bin);
      base.push_back(bin->size());
      fallback.push_back(is_meshopt_fallback(buffer));
      const std::string what = strprintf("buffers[%zu]", b);
      // EXT_meshopt_compression "Fallback buffers": the uncompressed copy is
      // for loaders without the extension; its views are decoded from their
      // compressed source instead (scene/gltf_decompress.h), so a fallback
      // file is not read.
      const bool skip = fallback.back() && buffer.contains("uri");
      if (!skip && buffer.contains("uri") && buffer["uri"].is_string()) {
        auto data = read_uri(buffer["uri"].get<std::string>(), base_dir, what);
        if (!data) return data.status();
        bin->insert(bin->end(), data.value().begin(), data.value().end());
      } else if (b == 0 && !skip) {
        bin->insert(bin->end(), glb_bin.begin(), glb_bin.end());
      }
      // (An unused buffer without data is valid glTF; nothing refers to it.)
    }
  }
  if (doc.contains("bufferViews")) {
    for (size_t v = 0; v < doc["bufferViews"].size(); ++v) {
      json& view = doc["bufferViews"][v];
      const size_t b = view.value("buffer", 0);
      if (b >= base.size())
        return invalid_argument(
            strprintf("bufferViews[%zu] names a buffer that does not exist", v));
      const bool compressed = view.contains("extensions") && view["extensions"].is_object() &&
                              view["extensions"].contains("EXT_meshopt_compression") &&
                              view["extensions"]["EXT_meshopt_compression"].is_object();
      // The README's "Fallback buffers": only compressed views refer to a
      // fallback buffer, and never as their compressed source.
      if (fallback[b] && !compressed)
        return invalid_argument(strprintf(
            "bufferViews[%zu]: buffer %zu is an EXT_meshopt_compression fallback buffer, and the "
            "view is not compressed",
            v, b));
      view["buffer"] = 0;
      view["byteOffset"] = view.value("byteOffset", size_t{0}) + base[b];
      if (!compressed) continue;
      json& ext = view["extensions"]["EXT_meshopt_compression"];
      const size_t source = ext.value("buffer", size_t{0});
      if (source >= base.size() || fallback[source])
        return invalid_argument(
            strprintf("bufferViews[%zu] (EXT_meshopt_compression): buffer %zu %s", v, source,
                      source >= base.size() ? "does not exist"
                                            : "is a fallback buffer, which holds no "
                                              "compressed data"));
      ext["buffer"] = 0;
      ext["byteOffset"] = ext.value("byteOffset", size_t{0}) + base[source];
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
      image["bufferView"] = append_buffer_view(d, data.value().data(), data.value().size(), 0);
    }
  }
  return Status::ok();
}

}  // namespace

int gltf_components(const std::string& type) {
  if (type == "SCALAR") return 1;
  if (type == "VEC2") return 2;
  if (type == "VEC3") return 3;
  if (type == "VEC4" || type == "MAT2") return 4;
  if (type == "MAT3") return 9;
  if (type == "MAT4") return 16;
  return 0;
}

int gltf_component_bytes(int component_type) {
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

Result<GltfDocument> read_gltf_document(std::string_view bytes, const std::string& base_dir) {
  GltfDocument d;
  Bytes glb_bin;
  LUXEL_RETURN_IF_ERROR(parse_container(bytes, &d.json, &glb_bin));
  LUXEL_RETURN_IF_ERROR(merge_buffers(&d, glb_bin, base_dir));
  if (!d.json.contains("accessors")) d.json["accessors"] = json::array();
  if (!d.json.contains("bufferViews")) d.json["bufferViews"] = json::array();
  return d;
}

int append_buffer_view(GltfDocument* d, const void* data, size_t bytes, int target) {
  align(&d->bin);
  json view = {{"buffer", 0}, {"byteOffset", d->bin.size()}, {"byteLength", bytes}};
  if (target) view["target"] = target;
  const auto* p = static_cast<const uint8_t*>(data);
  d->bin.insert(d->bin.end(), p, p + bytes);
  d->json["bufferViews"].push_back(view);
  return static_cast<int>(d->json["bufferViews"].size()) - 1;
}

Result<Bytes> read_accessor_elements(const GltfDocument& d, int index, size_t* element_size) {
  const json& doc = d.json;
  const Bytes& bin = d.bin;
  const std::string what = strprintf("accessors[%d]", index);
  if (index < 0 || !doc.contains("accessors") ||
      static_cast<size_t>(index) >= doc["accessors"].size())
    return invalid_argument(what + " does not exist");
  const json& a = doc["accessors"][static_cast<size_t>(index)];
  const size_t count = a.value("count", size_t{0});
  const size_t esize = static_cast<size_t>(gltf_component_bytes(a.value("componentType", 0)) *
                                           gltf_components(a.value("type", std::string())));
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
    const size_t isize = static_cast<size_t>(gltf_component_bytes(ictype));
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

std::string write_glb(GltfDocument d) {
  align(&d.bin);
  d.json["buffers"] = json::array({json{{"byteLength", d.bin.size()}}});
  std::string text = d.json.dump();
  while (text.size() % 4 != 0) text.push_back(' ');
  std::string out;
  auto put = [&](uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
  const uint32_t total = static_cast<uint32_t>(12 + 8 + text.size() + 8 + d.bin.size());
  put(kGlbMagic);
  put(2);
  put(total);
  put(static_cast<uint32_t>(text.size()));
  put(kChunkJson);
  out += text;
  put(static_cast<uint32_t>(d.bin.size()));
  put(kChunkBin);
  out.append(reinterpret_cast<const char*>(d.bin.data()), d.bin.size());
  return out;
}

}  // namespace luxel::scene
