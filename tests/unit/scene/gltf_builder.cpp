#include "gltf_builder.h"

#include <stb_image_write.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace luxel::test {

const std::vector<float> kQuadPositions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
const std::vector<uint32_t> kQuadIndices = {0, 1, 2, 0, 2, 3};

GltfBuilder::GltfBuilder() {
  doc = json::object();
  doc["asset"] = {{"version", "2.0"}};
  doc["scene"] = 0;
  doc["scenes"] = json::array({json::object({{"nodes", json::array()}})});
}

int GltfBuilder::add_view(const void* data, size_t bytes, int stride) {
  while (bin.size() % 4 != 0) bin.push_back(0);
  const size_t offset = bin.size();
  bin.resize(offset + bytes);
  if (bytes) std::memcpy(bin.data() + offset, data, bytes);
  json v = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}};
  if (stride) v["byteStride"] = stride;
  doc["bufferViews"].push_back(v);
  return static_cast<int>(doc["bufferViews"].size() - 1);
}

int GltfBuilder::add_accessor(int view, int component_type, size_t count, const char* type,
                              size_t byte_offset, bool normalized) {
  json a = {{"componentType", component_type}, {"count", count}, {"type", type}};
  if (view >= 0) a["bufferView"] = view;
  if (byte_offset) a["byteOffset"] = byte_offset;
  if (normalized) a["normalized"] = true;
  doc["accessors"].push_back(a);
  return static_cast<int>(doc["accessors"].size() - 1);
}

int GltfBuilder::add_floats(const std::vector<float>& values, const char* type) {
  const size_t comps = std::strcmp(type, "VEC2") == 0   ? 2
                       : std::strcmp(type, "VEC3") == 0 ? 3
                       : std::strcmp(type, "VEC4") == 0 ? 4
                                                        : 1;
  const int view = add_view(values.data(), values.size() * sizeof(float));
  return add_accessor(view, kFloat, values.size() / comps, type);
}

int GltfBuilder::add_indices(const std::vector<uint32_t>& indices, int component_type) {
  std::vector<uint8_t> raw;
  for (uint32_t i : indices) {
    if (component_type == kUByte) {
      raw.push_back(static_cast<uint8_t>(i));
    } else if (component_type == kUShort) {
      const auto v = static_cast<uint16_t>(i);
      raw.insert(raw.end(), reinterpret_cast<const uint8_t*>(&v),
                 reinterpret_cast<const uint8_t*>(&v) + 2);
    } else {
      raw.insert(raw.end(), reinterpret_cast<const uint8_t*>(&i),
                 reinterpret_cast<const uint8_t*>(&i) + 4);
    }
  }
  const int view = add_view(raw.data(), raw.size());
  return add_accessor(view, component_type, indices.size(), "SCALAR");
}

json GltfBuilder::triangles(const std::vector<float>& positions,
                            const std::vector<uint32_t>& indices, int index_type, bool with_uv1) {
  json prim = {{"attributes", {{"POSITION", add_floats(positions, "VEC3")}}}};
  if (with_uv1) {
    std::vector<float> uv;
    for (size_t i = 0; i + 2 < positions.size(); i += 3) {
      uv.push_back(positions[i] / 10.0f);
      uv.push_back(positions[i + 1] / 10.0f);
    }
    prim["attributes"]["TEXCOORD_1"] = add_floats(uv, "VEC2");
  }
  if (!indices.empty() && index_type) prim["indices"] = add_indices(indices, index_type);
  return prim;
}

int GltfBuilder::add_mesh(const std::string& name, const std::vector<json>& primitives) {
  json m = {{"primitives", primitives}};
  if (!name.empty()) m["name"] = name;
  doc["meshes"].push_back(m);
  return static_cast<int>(doc["meshes"].size() - 1);
}

int GltfBuilder::add_node_impl(json node, bool root) {
  doc["nodes"].push_back(std::move(node));
  const int index = static_cast<int>(doc["nodes"].size() - 1);
  if (root) doc["scenes"][0]["nodes"].push_back(index);
  return index;
}

int GltfBuilder::add_node(json node) {
  return add_node_impl(std::move(node), true);
}
int GltfBuilder::add_child_node(json node) {
  return add_node_impl(std::move(node), false);
}

int GltfBuilder::add_material(json material) {
  doc["materials"].push_back(std::move(material));
  return static_cast<int>(doc["materials"].size() - 1);
}

std::string base64(const std::string& bytes) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const uint32_t v =
        (uint8_t(bytes[i]) << 16) | (uint8_t(bytes[i + 1]) << 8) | uint8_t(bytes[i + 2]);
    out += {k[v >> 18], k[(v >> 12) & 63], k[(v >> 6) & 63], k[v & 63]};
  }
  if (i + 1 == bytes.size()) {
    const uint32_t v = uint8_t(bytes[i]) << 16;
    out += {k[v >> 18], k[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == bytes.size()) {
    const uint32_t v = (uint8_t(bytes[i]) << 16) | (uint8_t(bytes[i + 1]) << 8);
    out += {k[v >> 18], k[(v >> 12) & 63], k[(v >> 6) & 63], '='};
  }
  return out;
}

std::string GltfBuilder::gltf_embedded() const {
  json d = doc;
  if (!bin.empty()) {
    const std::string raw(bin.begin(), bin.end());
    d["buffers"] = json::array({{{"byteLength", bin.size()},
                                 {"uri", "data:application/octet-stream;base64," + base64(raw)}}});
  }
  return d.dump();
}

std::string GltfBuilder::gltf_external(const std::string& bin_uri) const {
  json d = doc;
  d["buffers"] = json::array({{{"byteLength", bin.size()}, {"uri", bin_uri}}});
  return d.dump();
}

std::string GltfBuilder::glb() const {
  json d = doc;
  if (!bin.empty()) d["buffers"] = json::array({{{"byteLength", bin.size()}}});
  std::string js = d.dump();
  while (js.size() % 4) js.push_back(' ');
  std::string b(bin.begin(), bin.end());
  while (b.size() % 4) b.push_back('\0');
  auto u32 = [](uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); };
  const uint32_t total = 12 + 8 + static_cast<uint32_t>(js.size()) +
                         (b.empty() ? 0 : 8 + static_cast<uint32_t>(b.size()));
  std::string out =
      "glTF" + u32(2) + u32(total) + u32(static_cast<uint32_t>(js.size())) + "JSON" + js;
  if (!b.empty()) out += u32(static_cast<uint32_t>(b.size())) + std::string("BIN\0", 4) + b;
  return out;
}

TempDir::TempDir() {
  std::string tmpl = (std::filesystem::temp_directory_path() / "luxel_scene_test_XXXXXX").string();
  if (!mkdtemp(tmpl.data())) throw std::runtime_error("mkdtemp failed");
  path_ = tmpl;
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

std::string TempDir::write(const std::string& name, const std::string& bytes) const {
  const std::string full = path_ + "/" + name;
  std::ofstream(full, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return full;
}

std::string encode_png(int w, int h, int channels, const std::vector<uint8_t>& pixels) {
  std::string out;
  stbi_write_png_to_func(
      [](void* ctx, void* data, int size) {
        static_cast<std::string*>(ctx)->append(static_cast<char*>(data), static_cast<size_t>(size));
      },
      &out, w, h, channels, pixels.data(), w * channels);
  return out;
}

namespace {

uint32_t crc32(const std::string& data) {
  uint32_t c = 0xFFFFFFFFu;
  for (unsigned char byte : data) {
    c ^= byte;
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
  }
  return ~c;
}

std::string be32(uint32_t v) {
  return {static_cast<char>(v >> 24), static_cast<char>(v >> 16), static_cast<char>(v >> 8),
          static_cast<char>(v)};
}

std::string png_chunk(const std::string& type, const std::string& data) {
  return be32(static_cast<uint32_t>(data.size())) + type + data + be32(crc32(type + data));
}

}  // namespace

std::string encode_png16_gray(int w, int h, const std::vector<uint16_t>& pixels) {
  std::string raw;
  for (int y = 0; y < h; ++y) {
    raw.push_back('\0');  // filter: none
    for (int x = 0; x < w; ++x) {
      const uint16_t v = pixels[static_cast<size_t>(y * w + x)];
      raw += {static_cast<char>(v >> 8), static_cast<char>(v & 0xFF)};
    }
  }
  // zlib stream: header, one stored block (raw must stay below 64 KiB), adler32.
  uint32_t a = 1, b = 0;
  for (unsigned char c : raw) {
    a = (a + c) % 65521;
    b = (b + a) % 65521;
  }
  const auto len = static_cast<uint16_t>(raw.size());
  std::string z = {'\x78',
                   '\x01',
                   '\x01',
                   static_cast<char>(len & 0xFF),
                   static_cast<char>(len >> 8),
                   static_cast<char>(~len & 0xFF),
                   static_cast<char>((~len >> 8) & 0xFF)};
  z += raw + be32((b << 16) | a);
  const std::string ihdr = be32(static_cast<uint32_t>(w)) + be32(static_cast<uint32_t>(h)) +
                           std::string("\x10\0\0\0\0", 5);
  return std::string("\x89PNG\r\n\x1a\n", 8) + png_chunk("IHDR", ihdr) + png_chunk("IDAT", z) +
         png_chunk("IEND", "");
}

std::string read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

json glb_json(const std::string& bytes) {
  uint32_t length = 0;
  if (bytes.size() < 20) return json();
  std::memcpy(&length, bytes.data() + 12, 4);
  return json::parse(bytes.substr(20, length));
}

}  // namespace luxel::test
