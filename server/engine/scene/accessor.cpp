// See accessor.h. Sparse accessors are supported: the base values (from the
// buffer view, or zeros without one) are read first, then sparse.count
// (index, value) pairs replace elements, as the glTF spec describes.
#include "scene/accessor.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace luxel::scene::detail {
namespace {

unsigned component_bit(int ct) {
  switch (ct) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
      return kCompI8;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return kCompU8;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
      return kCompI16;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
      return kCompU16;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
      return kCompU32;
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
      return kCompF32;
    default:
      return 0;
  }
}

uint64_t component_size(int ct) {
  switch (component_bit(ct)) {
    case kCompI8:
    case kCompU8:
      return 1;
    case kCompI16:
    case kCompU16:
      return 2;
    case kCompU32:
    case kCompF32:
      return 4;
    default:
      return 0;
  }
}

int type_components(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR:
      return 1;
    case TINYGLTF_TYPE_VEC2:
      return 2;
    case TINYGLTF_TYPE_VEC3:
      return 3;
    case TINYGLTF_TYPE_VEC4:
      return 4;
    default:
      return 0;  // matrices are never vertex attributes here
  }
}

const char* type_name(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR:
      return "SCALAR";
    case TINYGLTF_TYPE_VEC2:
      return "VEC2";
    case TINYGLTF_TYPE_VEC3:
      return "VEC3";
    case TINYGLTF_TYPE_VEC4:
      return "VEC4";
    case TINYGLTF_TYPE_MAT2:
      return "MAT2";
    case TINYGLTF_TYPE_MAT3:
      return "MAT3";
    case TINYGLTF_TYPE_MAT4:
      return "MAT4";
    default:
      return "unknown";
  }
}

// Reads one component as a float (normalized integers mapped per the spec).
double load_component(const uint8_t* p, int ct, bool normalized) {
  switch (ct) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: {
      float f;
      std::memcpy(&f, p, 4);
      return static_cast<double>(f);
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return normalized ? p[0] / 255.0 : p[0];
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
      const auto v = static_cast<int8_t>(p[0]);
      return normalized ? std::max(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      uint16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? v / 65535.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
      int16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? std::max(v / 32767.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
      uint32_t v;
      std::memcpy(&v, p, 4);
      return v;
    }
    default:
      return 0;
  }
}

uint32_t load_index(const uint8_t* p, int ct) {
  switch (ct) {
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return p[0];
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      uint16_t v;
      std::memcpy(&v, p, 2);
      return v;
    }
    default: {
      uint32_t v;
      std::memcpy(&v, p, 4);
      return v;
    }
  }
}

// A validated strided run of `count` elements of `elem_size` bytes.
struct Run {
  const uint8_t* base = nullptr;
  uint64_t stride = 0;
};

// Locates `count` elements at byte_offset inside buffer view `view`. `who` is
// the message prefix. stride_allowed: false for index and sparse data, which
// are tightly packed by definition.
Status locate(const tinygltf::Model& model, int view, uint64_t byte_offset, uint64_t count,
              uint64_t elem_size, bool stride_allowed, const std::string& who, Run* run) {
  auto bytes = buffer_view_bytes(model, view, who);
  if (!bytes) return bytes.status();
  const auto& bv = model.bufferViews[static_cast<size_t>(view)];
  uint64_t stride = elem_size;
  if (bv.byteStride != 0 && stride_allowed) {
    if (static_cast<uint64_t>(bv.byteStride) < elem_size) {
      return invalid_argument(strprintf("%s: byteStride %llu is smaller than the element size %llu",
                                        who.c_str(), static_cast<unsigned long long>(bv.byteStride),
                                        static_cast<unsigned long long>(elem_size)));
    }
    stride = static_cast<uint64_t>(bv.byteStride);
  }
  run->base = reinterpret_cast<const uint8_t*>(bytes->data());
  run->stride = stride;
  if (count == 0) return Status::ok();
  // Last byte read: byte_offset + (count - 1) * stride + elem_size.
  uint64_t end = 0;
  if (__builtin_mul_overflow(count - 1, stride, &end) ||
      __builtin_add_overflow(end, elem_size, &end) ||
      __builtin_add_overflow(end, byte_offset, &end) || end > bytes->size()) {
    return invalid_argument(strprintf(
        "%s: byteOffset %llu + %llu elements of %llu bytes (stride %llu) overrun "
        "bufferView %d (byteLength %zu)",
        who.c_str(), static_cast<unsigned long long>(byte_offset),
        static_cast<unsigned long long>(count), static_cast<unsigned long long>(elem_size),
        static_cast<unsigned long long>(stride), view, bytes->size()));
  }
  run->base += byte_offset;
  return Status::ok();
}

// Validates and reads the raw components of an accessor (with sparse
// substitution) as doubles; the caller interprets them.
// `staging` reserves the doubles; `out_reserved` the caller's result, 4
// bytes per component.
Status read_components(const tinygltf::Model& model, int index, const char* semantic, int type,
                       unsigned allowed, unsigned unnormalized, const std::string& ctx,
                       ImportBudget* budget, ScopedReservation* staging,
                       ScopedReservation* out_reserved, std::vector<double>* out) {
  const std::string who = strprintf("%s: accessor %d (%s)", ctx.c_str(), index, semantic);
  if (index < 0 || static_cast<size_t>(index) >= model.accessors.size()) {
    return invalid_argument(strprintf("%s: accessor %d (%s) does not exist (%zu accessors)",
                                      ctx.c_str(), index, semantic, model.accessors.size()));
  }
  const auto& acc = model.accessors[static_cast<size_t>(index)];
  const unsigned bit = component_bit(acc.componentType);
  const bool is_int = bit != kCompF32;
  if ((bit & (allowed | unnormalized)) == 0) {
    return invalid_argument(strprintf("%s: componentType %d (%s) is not allowed for %s",
                                      who.c_str(), acc.componentType,
                                      component_type_name(acc.componentType), semantic));
  }
  if (acc.type != type) {
    return invalid_argument(
        strprintf("%s: type %s, expected %s", who.c_str(), type_name(acc.type), type_name(type)));
  }
  if (is_int && type != TINYGLTF_TYPE_SCALAR && !acc.normalized && (bit & unnormalized) == 0) {
    return invalid_argument(strprintf("%s: integer componentType %s must be normalized",
                                      who.c_str(), component_type_name(acc.componentType)));
  }
  if (is_int && acc.normalized && (bit & allowed) == 0) {
    return invalid_argument(strprintf("%s: componentType %s must not be normalized for %s",
                                      who.c_str(), component_type_name(acc.componentType),
                                      semantic));
  }
  const uint64_t count = acc.count;
  if (count > budget->elements_left) {
    return resource_exhausted(strprintf("%s: count %llu exceeds the import's element limit",
                                        who.c_str(), static_cast<unsigned long long>(count)));
  }
  budget->elements_left -= count;
  const auto comps = static_cast<uint64_t>(type_components(type));
  const uint64_t csize = component_size(acc.componentType);
  const uint64_t elem = comps * csize;

  Run run;
  if (acc.bufferView >= 0) {
    LUXEL_RETURN_IF_ERROR(
        locate(model, acc.bufferView, acc.byteOffset, count, elem, true, who, &run));
  }
  {
    const std::string what = strprintf("%s: %llu elements of %s", who.c_str(),
                                       static_cast<unsigned long long>(count), type_name(type));
    LUXEL_RETURN_IF_ERROR(staging->reserve(mul_sat(count, comps, kStagingBytesPerComponent), what));
    LUXEL_RETURN_IF_ERROR(
        out_reserved->reserve(mul_sat(count, comps, kFloatBytesPerComponent), what));
  }
  // Without a bufferView the base values are zeros (spec); their memory is
  // bounded by the element budget checked above, not by the file size.
  out->assign(count * comps, 0.0);
  if (run.base != nullptr) {
    for (uint64_t i = 0; i < count; ++i) {
      if (i % kDeadlineStride == kDeadlineStride - 1)
        LUXEL_RETURN_IF_ERROR(budget->check_deadline(who));
      const uint8_t* p = run.base + i * run.stride;
      for (uint64_t c = 0; c < comps; ++c)
        (*out)[i * comps + c] = load_component(p + c * csize, acc.componentType, acc.normalized);
    }
  }

  if (acc.sparse.isSparse) {
    const auto& sp = acc.sparse;
    if (sp.count < 1 || static_cast<uint64_t>(sp.count) > count) {
      return invalid_argument(strprintf("%s: sparse.count %d must be in 1..count (%llu)",
                                        who.c_str(), sp.count,
                                        static_cast<unsigned long long>(count)));
    }
    const int ict = sp.indices.componentType;
    if ((component_bit(ict) & (kCompU8 | kCompU16 | kCompU32)) == 0) {
      return invalid_argument(strprintf(
          "%s: sparse.indices.componentType %d is not an unsigned integer type", who.c_str(), ict));
    }
    if (sp.indices.byteOffset < 0 || sp.values.byteOffset < 0) {
      return invalid_argument(who + ": negative sparse byteOffset");
    }
    const auto n = static_cast<uint64_t>(sp.count);
    Run ir, vr;
    LUXEL_RETURN_IF_ERROR(locate(model, sp.indices.bufferView,
                                 static_cast<uint64_t>(sp.indices.byteOffset), n,
                                 component_size(ict), false, who + " sparse.indices", &ir));
    LUXEL_RETURN_IF_ERROR(locate(model, sp.values.bufferView,
                                 static_cast<uint64_t>(sp.values.byteOffset), n, elem, false,
                                 who + " sparse.values", &vr));
    for (uint64_t k = 0; k < n; ++k) {
      const uint64_t target = load_index(ir.base + k * ir.stride, ict);
      if (target >= count) {
        return invalid_argument(strprintf("%s: sparse index %llu is out of range (count %llu)",
                                          who.c_str(), static_cast<unsigned long long>(target),
                                          static_cast<unsigned long long>(count)));
      }
      for (uint64_t c = 0; c < comps; ++c) {
        (*out)[target * comps + c] =
            load_component(vr.base + k * vr.stride + c * csize, acc.componentType, acc.normalized);
      }
    }
  }
  return Status::ok();
}

}  // namespace

const char* component_type_name(int ct) {
  switch (ct) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
      return "BYTE";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return "UNSIGNED_BYTE";
    case TINYGLTF_COMPONENT_TYPE_SHORT:
      return "SHORT";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
      return "UNSIGNED_SHORT";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
      return "UNSIGNED_INT";
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
      return "FLOAT";
    case TINYGLTF_COMPONENT_TYPE_DOUBLE:
      return "DOUBLE";
    case TINYGLTF_COMPONENT_TYPE_INT:
      return "INT";
    default:
      return "invalid";
  }
}

Result<std::string_view> buffer_view_bytes(const tinygltf::Model& model, int view,
                                           const std::string& ctx) {
  if (view < 0 || static_cast<size_t>(view) >= model.bufferViews.size()) {
    return invalid_argument(strprintf("%s: bufferView %d does not exist (%zu bufferViews)",
                                      ctx.c_str(), view, model.bufferViews.size()));
  }
  const auto& bv = model.bufferViews[static_cast<size_t>(view)];
  if (bv.buffer < 0 || static_cast<size_t>(bv.buffer) >= model.buffers.size()) {
    return invalid_argument(strprintf("%s: bufferView %d refers to buffer %d, which does not exist",
                                      ctx.c_str(), view, bv.buffer));
  }
  const auto& buffer = model.buffers[static_cast<size_t>(bv.buffer)];
  const auto& data = buffer.data;
  const uint64_t size = data.size();
  if (data.empty() && buffer.uri.empty() && bv.byteLength > 0) {
    return invalid_argument(
        strprintf("%s: bufferView %d refers to buffer %d, which has no data (no uri; only the "
                  "first buffer of a .glb may omit it)",
                  ctx.c_str(), view, bv.buffer));
  }
  if (bv.byteOffset > size || bv.byteLength > size - bv.byteOffset) {
    return data_loss(strprintf(
        "%s: bufferView %d (byteOffset %zu, byteLength %zu) overruns buffer %d (%llu bytes)",
        ctx.c_str(), view, bv.byteOffset, bv.byteLength, bv.buffer,
        static_cast<unsigned long long>(size)));
  }
  return std::string_view(reinterpret_cast<const char*>(data.data()) + bv.byteOffset,
                          bv.byteLength);
}

uint64_t declared_count(const tinygltf::Model& model, int index) {
  if (index < 0 || static_cast<size_t>(index) >= model.accessors.size()) return 0;
  const auto& acc = model.accessors[static_cast<size_t>(index)];
  if (acc.bufferView < 0) return acc.count;
  const uint64_t elem = static_cast<uint64_t>(std::max(type_components(acc.type), 1)) *
                        std::max<uint64_t>(component_size(acc.componentType), 1);
  Run run;
  if (!locate(model, acc.bufferView, acc.byteOffset, acc.count, elem, true, "", &run).is_ok())
    return 0;
  return acc.count;
}

Status read_floats(const tinygltf::Model& model, int index, const char* semantic, int type,
                   unsigned normalized, unsigned unnormalized, const std::string& ctx,
                   ImportBudget* budget, ScopedReservation* out_reserved, std::vector<float>* out) {
  ScopedReservation staging(budget);
  std::vector<double> values;
  LUXEL_RETURN_IF_ERROR(read_components(model, index, semantic, type, normalized, unnormalized, ctx,
                                        budget, &staging, out_reserved, &values));
  const auto comps = static_cast<size_t>(type_components(type));
  out->resize(values.size());
  for (size_t i = 0; i < values.size(); ++i) {
    const double v = values[i];
    // Also catches finite doubles that overflow float (none come from float
    // data, but normalized data cannot produce them either).
    if (!std::isfinite(v)) {
      return invalid_argument(strprintf("%s: accessor %d (%s): element %zu component %zu is %s",
                                        ctx.c_str(), index, semantic, i / comps, i % comps,
                                        std::isnan(v) ? "NaN" : "infinite"));
    }
    (*out)[i] = static_cast<float>(v);
  }
  return Status::ok();
}

Status read_indices(const tinygltf::Model& model, int index, const std::string& ctx,
                    ImportBudget* budget, ScopedReservation* out_reserved,
                    std::vector<uint32_t>* out) {
  ScopedReservation staging(budget);
  std::vector<double> values;
  LUXEL_RETURN_IF_ERROR(read_components(model, index, "indices", TINYGLTF_TYPE_SCALAR,
                                        kCompU8 | kCompU16 | kCompU32, 0, ctx, budget, &staging,
                                        out_reserved, &values));
  out->resize(values.size());
  for (size_t i = 0; i < values.size(); ++i) (*out)[i] = static_cast<uint32_t>(values[i]);
  return Status::ok();
}

}  // namespace luxel::scene::detail
