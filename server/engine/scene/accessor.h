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
#include "scene/import_budget.h"
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
// are errors. `budget`: its element count is decremented by the accessor's
// count; the double staging of the read is reserved while it lasts and the
// result (4 bytes per component) stays reserved in `out_reserved` (the
// caller's scope releases it with the vector). Both are reserved before they
// are allocated, so a declared count that does not fit is refused without
// allocating (RESOURCE_EXHAUSTED naming the accessor and the bytes).
Status read_floats(const tinygltf::Model& model, int index, const char* semantic, int type,
                   unsigned normalized, unsigned unnormalized, const std::string& ctx,
                   ImportBudget* budget, ScopedReservation* out_reserved, std::vector<float>* out);

// Reads an index accessor (SCALAR, u8/u16/u32); budget as for read_floats.
Status read_indices(const tinygltf::Model& model, int index, const std::string& ctx,
                    ImportBudget* budget, ScopedReservation* out_reserved,
                    std::vector<uint32_t>* out);

// The count of accessor `index` as the file declares it, for reserving what
// reading it allocates before it is read; 0 when the accessor does not exist
// or its elements overrun its bufferView (read_floats reports those as
// invalid, before it allocates).
uint64_t declared_count(const tinygltf::Model& model, int index);

// The bytes of a buffer view, checked against its buffer.
Result<std::string_view> buffer_view_bytes(const tinygltf::Model& model, int view,
                                           const std::string& ctx);

// "accessor 5 (POSITION)" style names of component types for messages.
const char* component_type_name(int component_type);

}  // namespace luxel::scene::detail
