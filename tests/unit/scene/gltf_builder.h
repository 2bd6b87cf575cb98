// Test helper: builds small glTF documents in memory (JSON + one binary
// buffer) and writes them as .gltf with an embedded or external buffer, or as
// .glb. Crafted test files are generated here instead of being committed.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace luxel::test {

using nlohmann::json;

constexpr int kByte = 5120, kUByte = 5121, kShort = 5122, kUShort = 5123, kUInt = 5125,
              kFloat = 5126;

class GltfBuilder {
 public:
  GltfBuilder();

  json doc;                  // edit freely; "buffers" is filled on output
  std::vector<uint8_t> bin;  // the single buffer

  // Appends raw bytes (4-byte aligned) as a bufferView; returns its index.
  int add_view(const void* data, size_t bytes, int stride = 0);
  // Adds an accessor on `view`; returns its index.
  int add_accessor(int view, int component_type, size_t count, const char* type,
                   size_t byte_offset = 0, bool normalized = false);
  // bufferView + accessor for float data (`type` VEC2/VEC3/VEC4/SCALAR).
  int add_floats(const std::vector<float>& values, const char* type);
  // bufferView + accessor for indices of the given component type.
  int add_indices(const std::vector<uint32_t>& indices, int component_type = kUInt);

  // A triangle primitive from positions (xyz) with TEXCOORD_1 = xy / 10 and
  // optional indices (component type `index_type`, 0: non-indexed).
  json triangles(const std::vector<float>& positions, const std::vector<uint32_t>& indices = {},
                 int index_type = kUInt, bool with_uv1 = true);
  int add_mesh(const std::string& name, const std::vector<json>& primitives);
  int add_node(json node);  // also lists it as a root of scene 0 unless `child` is true
  int add_child_node(json node);
  int add_material(json material);

  // Serializations. The buffer (if any) is buffer 0.
  std::string gltf_embedded() const;                            // data: URI
  std::string gltf_external(const std::string& bin_uri) const;  // uri = bin_uri
  std::string glb() const;

 private:
  int add_node_impl(json node, bool root);
};

// A fresh temporary folder, removed with its files on destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::string& path() const { return path_; }
  std::string write(const std::string& name,
                    const std::string& bytes) const;  // returns the full path

 private:
  std::string path_;
};

std::string base64(const std::string& bytes);

// A PNG of w x h RGBA8 pixels (stb_image_write).
std::string encode_png(int w, int h, int channels, const std::vector<uint8_t>& pixels);

// A 16-bit greyscale PNG (hand-written: stb_image_write has no 16-bit PNG),
// stored with an uncompressed deflate block.
std::string encode_png16_gray(int w, int h, const std::vector<uint16_t>& pixels);

// A whole file's bytes ("" when it cannot be read).
std::string read_all(const std::string& path);

// The JSON chunk of a GLB, parsed independently of Luxel's readers.
json glb_json(const std::string& bytes);

// A unit quad in the XY plane (z = 0), two triangles wound counter-clockwise
// seen from +Z: positions and indices.
extern const std::vector<float> kQuadPositions;
extern const std::vector<uint32_t> kQuadIndices;

}  // namespace luxel::test
