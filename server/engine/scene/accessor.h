// Checked reads of glTF accessors.
//
// Every offset, stride and count is checked against its bufferView and buffer
// (64-bit, overflow-safe) before a byte is read: tinygltf parses these numbers
// but does not relate them to each other. Errors name the accessor and the
// attribute, prefixed by the caller's context ("mesh 'floor' (mesh[2])
// primitive 0").
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "common/status.h"
#include "scene/tinygltf_config.h"

namespace luxel::scene::detail {

// Component types an attribute accepts, one bit each.
enum ComponentBits : unsigned {
  kCompI8 = 1u << 0,
  kCompU8 = 1u << 1,
  kCompI16 = 1u << 2,
  kCompU16 = 1u << 3,
  kCompU32 = 1u << 4,
  kCompF32 = 1u << 5,
};

// Reads accessor `index` (tinygltf type `type`, e.g. TINYGLTF_TYPE_VEC3) as
// floats, `components` per element, appended to `out` after clearing it.
// `normalized` lists the component types accepted with normalized: true
// (mapped to [0,1] or [-1,1]) and FLOAT; `unnormalized` the integer types
// accepted as plain integer values (KHR_mesh_quantization). Non-finite values
// are errors. `budget` is the number of elements still allowed for this
// import (decremented).
Status read_floats(const tinygltf::Model& model, int index, const char* semantic, int type,
                   unsigned normalized, unsigned unnormalized, const std::string& ctx,
                   uint64_t* budget, std::vector<float>* out);

// Reads an index accessor (SCALAR, u8/u16/u32).
Status read_indices(const tinygltf::Model& model, int index, const std::string& ctx,
                    uint64_t* budget, std::vector<uint32_t>* out);

// The bytes of a buffer view, checked against its buffer.
Result<std::string_view> buffer_view_bytes(const tinygltf::Model& model, int view,
                                           const std::string& ctx);

// "accessor 5 (POSITION)" style names of component types for messages.
const char* component_type_name(int component_type);

}  // namespace luxel::scene::detail
