// A glTF file as JSON plus one binary buffer: every buffer (GLB chunk, data
// URIs, external files) merged into buffer 0 and external images embedded.
// The form in which Luxel edits a file it did not write: members it does not
// know survive, because the JSON is kept as it is (nlohmann::json) instead of
// going through tinygltf's model. Used by the write-back of generated lightmap
// UVs (post/lightmapped_gltf.h) and by the decoding of compressed geometry
// (scene/gltf_decompress.h).
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "common/status.h"

namespace luxel::scene {

using Bytes = std::vector<uint8_t>;

struct GltfDocument {
  nlohmann::json json;  // the file's JSON; buffers[0] describes `bin`
  Bytes bin;            // the one buffer every bufferView points into
};

// glTF 2.0 §3.7.2 / §3.11: component and element sizes (0 when unknown).
int gltf_components(const std::string& type);
int gltf_component_bytes(int component_type);

// Reads a .gltf or .glb from memory; `base_dir` resolves external URIs ("":
// they are refused). The result has one buffer and self-contained images.
// EXT_meshopt_compression: a view's compressed source range is rebased like
// the view; fallback buffers are not read (their views are garbage until
// decompress_geometry decodes them).
Result<GltfDocument> read_gltf_document(std::string_view bytes, const std::string& base_dir);

// Appends `bytes` of data as a new bufferView of buffer 0 (4-byte aligned,
// glTF 2.0 §3.6.2.4); `target` 0 leaves it unset. Returns its index.
int append_buffer_view(GltfDocument* doc, const void* data, size_t bytes, int target);

// Accessor `index`'s elements, tightly packed: stride removed, sparse
// substitution applied, zeros without a bufferView (glTF 2.0 §3.6.2.3).
// `element_size` receives the bytes per element.
Result<Bytes> read_accessor_elements(const GltfDocument& doc, int index, size_t* element_size);

// The document as a GLB (glTF 2.0 §4.4), its one buffer the binary chunk.
std::string write_glb(GltfDocument doc);

}  // namespace luxel::scene
