// See gltf_decompress.h. meshopt bufferViews are decoded first: a Draco
// bitstream could itself lie in a meshopt-compressed view.
#include "scene/gltf_decompress.h"

#include <draco/compression/decode.h>
#include <meshoptimizer.h>

#include <cstring>
#include <map>
#include <string>
#include <vector>

namespace luxel::scene {
namespace {

using nlohmann::json;

constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

bool has_extension(const json& o, const char* name) {
  return o.is_object() && o.contains("extensions") && o["extensions"].is_object() &&
         o["extensions"].contains(name);
}

void erase_extension(json* o, const char* name) {
  (*o)["extensions"].erase(name);
  if ((*o)["extensions"].empty()) o->erase("extensions");
}

// A non-negative integer member (nullopt-like: false when absent or of
// another type).
bool get_uint(const json& o, const char* key, uint64_t* out) {
  auto it = o.find(key);
  if (it == o.end() || !it->is_number_unsigned()) return false;
  *out = it->get<uint64_t>();
  return true;
}

void align4(Bytes* bin) {
  while (bin->size() % 4 != 0) bin->push_back(0);
}

Status charge(uint64_t n, uint64_t* budget, const std::string& what) {
  if (n > *budget)
    return resource_exhausted(
        strprintf("%s: %llu decoded elements exceed the import's element limit (%llu remain of it)",
                  what.c_str(), static_cast<unsigned long long>(n),
                  static_cast<unsigned long long>(*budget)));
  *budget -= n;
  return Status::ok();
}

// Reserves the bytes a decode will produce (kept until the import ends: the
// decoded document becomes the .glb that is loaded) and checks the deadline.
Status charge_bytes(detail::ImportBudget* budget, uint64_t bytes, const std::string& what) {
  if (budget == nullptr) return Status::ok();
  LUXEL_RETURN_IF_ERROR(budget->check_deadline(what));
  return budget->reserve(bytes, what);
}

// ---- EXT_meshopt_compression -------------------------------------------

// One compressed bufferView, decoded and appended; the view then points to
// the decoded bytes. The checks are the README's "JSON schema updates"
// (the conditions for a valid extension object); meshoptimizer asserts
// rather than reports most of them.
Status decode_meshopt_view(GltfDocument* doc, size_t index, uint64_t* budget,
                           detail::ImportBudget* bytes) {
  json& view = doc->json["bufferViews"][index];
  const json& e = view["extensions"][kMeshoptExtension];
  const std::string what = strprintf("bufferViews[%zu] (%s)", index, kMeshoptExtension);
  auto bad = [&](const std::string& why) { return invalid_argument(what + ": " + why); };
  if (!e.is_object()) return bad("the extension is not a JSON object");
  uint64_t offset = 0, length = 0, stride = 0, count = 0, view_length = 0;
  get_uint(e, "byteOffset", &offset);
  if (!get_uint(e, "byteLength", &length) || !get_uint(e, "byteStride", &stride) ||
      !get_uint(e, "count", &count))
    return bad("byteLength, byteStride and count must be non-negative integers");
  if (!get_uint(view, "byteLength", &view_length))
    return bad("the bufferView's byteLength is missing");
  const std::string mode = e.value("mode", std::string());
  const std::string filter = e.contains("filter") && e["filter"].is_string()
                                 ? e["filter"].get<std::string>()
                                 : std::string("NONE");
  uint64_t parent_stride = 0;
  if (get_uint(view, "byteStride", &parent_stride) && parent_stride != stride)
    return bad(strprintf("byteStride %llu differs from the bufferView's %llu",
                         static_cast<unsigned long long>(stride),
                         static_cast<unsigned long long>(parent_stride)));
  if (stride == 0 || count > view_length / stride || count * stride != view_length)
    return bad(strprintf("count %llu x byteStride %llu is not the bufferView's byteLength %llu",
                         static_cast<unsigned long long>(count),
                         static_cast<unsigned long long>(stride),
                         static_cast<unsigned long long>(view_length)));
  if (mode == "ATTRIBUTES") {
    if (stride % 4 != 0 || stride > 256)
      return bad("mode ATTRIBUTES needs a byteStride divisible by 4 and at most 256");
  } else if (mode == "TRIANGLES" || mode == "INDICES") {
    if (stride != 2 && stride != 4) return bad("mode " + mode + " needs a byteStride of 2 or 4");
    if (mode == "TRIANGLES" && count % 3 != 0)
      return bad("mode TRIANGLES needs a count divisible by 3");
    if (filter != "NONE") return bad("mode " + mode + " allows no filter, not " + filter);
  } else {
    return bad("mode '" + mode + "' is not ATTRIBUTES, TRIANGLES or INDICES");
  }
  if (filter == "OCTAHEDRAL" && stride != 4 && stride != 8)
    return bad("filter OCTAHEDRAL needs a byteStride of 4 or 8");
  if (filter == "QUATERNION" && stride != 8)
    return bad("filter QUATERNION needs a byteStride of 8");
  if (filter != "NONE" && filter != "OCTAHEDRAL" && filter != "QUATERNION" &&
      filter != "EXPONENTIAL")
    return bad("filter '" + filter + "' is not NONE, OCTAHEDRAL, QUATERNION or EXPONENTIAL");
  // (EXPONENTIAL needs a byteStride divisible by 4, which ATTRIBUTES has.)
  if (offset > doc->bin.size() || length > doc->bin.size() - offset)
    return bad(strprintf(
        "the compressed data (byteOffset %llu, byteLength %llu) runs past its "
        "buffer",
        static_cast<unsigned long long>(offset), static_cast<unsigned long long>(length)));
  LUXEL_RETURN_IF_ERROR(charge(count, budget, what));
  // The decoded view, and its copy in the .glb written from the document.
  LUXEL_RETURN_IF_ERROR(charge_bytes(
      bytes, detail::mul_sat(count, stride, 2),
      what + strprintf(": %llu elements of %llu bytes", static_cast<unsigned long long>(count),
                       static_cast<unsigned long long>(stride))));

  Bytes out(count * stride);
  const unsigned char* src = doc->bin.data() + offset;
  int rc = 0;
  if (mode == "ATTRIBUTES") {
    rc = meshopt_decodeVertexBuffer(out.data(), count, stride, src, length);
  } else if (mode == "TRIANGLES") {
    rc = meshopt_decodeIndexBuffer(out.data(), count, stride, src, length);
  } else {
    rc = meshopt_decodeIndexSequence(out.data(), count, stride, src, length);
  }
  if (rc != 0)
    return bad(
        strprintf("the %s data does not decode (meshoptimizer error %d): corrupt or "
                  "truncated",
                  mode.c_str(), rc));
  // Appendix B (Filters): applied in place after the attribute decoder.
  if (filter == "OCTAHEDRAL") meshopt_decodeFilterOct(out.data(), count, stride);
  if (filter == "QUATERNION") meshopt_decodeFilterQuat(out.data(), count, stride);
  if (filter == "EXPONENTIAL") meshopt_decodeFilterExp(out.data(), count, stride);

  align4(&doc->bin);
  view["buffer"] = 0;
  view["byteOffset"] = doc->bin.size();
  doc->bin.insert(doc->bin.end(), out.begin(), out.end());
  erase_extension(&view, kMeshoptExtension);
  return Status::ok();
}

// ---- KHR_draco_mesh_compression ----------------------------------------

template <typename T>
void put(Bytes* out, T v) {
  const auto* p = reinterpret_cast<const uint8_t*>(&v);
  out->insert(out->end(), p, p + sizeof(T));
}

// Component values of one decoded attribute converted to the accessor's
// component type (Draco normalises integer <-> float as the attribute says).
template <typename T>
bool convert_attribute(const draco::Mesh& mesh, const draco::PointAttribute& attr, int comps,
                       Bytes* out, std::vector<double>* lo, std::vector<double>* hi) {
  std::vector<T> v(static_cast<size_t>(comps));
  lo->assign(static_cast<size_t>(comps), std::numeric_limits<double>::infinity());
  hi->assign(static_cast<size_t>(comps), -std::numeric_limits<double>::infinity());
  out->reserve(mesh.num_points() * sizeof(T) * static_cast<size_t>(comps));
  for (draco::PointIndex i(0); i < mesh.num_points(); ++i) {
    if (!attr.ConvertValue<T>(attr.mapped_index(i), static_cast<int8_t>(comps), v.data()))
      return false;
    for (size_t c = 0; c < v.size(); ++c) {
      put(out, v[c]);
      (*lo)[c] = std::min((*lo)[c], static_cast<double>(v[c]));
      (*hi)[c] = std::max((*hi)[c], static_cast<double>(v[c]));
    }
  }
  return true;
}

// A rewritten accessor: the old one's members (name, type, normalized...)
// without its data location, on a new bufferView. min/max are recomputed
// where the old one had them (glTF 2.0 §5.1: POSITION needs them), since
// Draco's quantisation moves the values.
void set_accessor(GltfDocument* doc, json* a, const Bytes& data, int target, size_t count,
                  const std::vector<double>& lo, const std::vector<double>& hi) {
  a->erase("sparse");
  a->erase("byteOffset");
  (*a)["bufferView"] = append_buffer_view(doc, data.data(), data.size(), target);
  (*a)["count"] = count;
  if (a->contains("min") && !lo.empty() && count > 0) (*a)["min"] = lo;
  if (a->contains("max") && !hi.empty() && count > 0) (*a)["max"] = hi;
}

struct DracoContext {
  std::map<int, bool> rewritten;  // accessors already given decoded data
};

// The accessor index the primitive's rewritten `slot` uses: in place the
// first time, a copy when an earlier Draco primitive already filled it.
json* target_accessor(GltfDocument* doc, DracoContext* ctx, json* slot) {
  const int a = slot->get<int>();
  json& accessors = doc->json["accessors"];
  if (!ctx->rewritten[a]) {
    ctx->rewritten[a] = true;
    return &accessors[static_cast<size_t>(a)];
  }
  accessors.push_back(accessors[static_cast<size_t>(a)]);
  *slot = accessors.size() - 1;
  ctx->rewritten[static_cast<int>(accessors.size()) - 1] = true;
  return &accessors.back();
}

Status decode_draco_primitive(GltfDocument* doc, size_t m, size_t p, DracoContext* ctx,
                              uint64_t* budget, detail::ImportBudget* bytes) {
  json& mesh = doc->json["meshes"][m];
  json& prim = mesh["primitives"][p];
  const std::string name = mesh.value("name", std::string());
  const std::string what = (name.empty() ? strprintf("mesh[%zu]", m)
                                         : strprintf("mesh '%s' (mesh[%zu])", name.c_str(), m)) +
                           strprintf(" primitive %zu (%s)", p, kDracoExtension);
  auto bad = [&](const std::string& why) { return invalid_argument(what + ": " + why); };
  const json ext = prim["extensions"][kDracoExtension];
  const json& accessors = doc->json["accessors"];
  uint64_t view_index = 0;
  if (!ext.is_object() || !get_uint(ext, "bufferView", &view_index) ||
      view_index >= doc->json["bufferViews"].size())
    return bad("bufferView is missing or names no bufferView");
  if (!ext.contains("attributes") || !ext["attributes"].is_object())
    return bad("attributes is missing or not an object");
  if (!prim.contains("attributes") || !prim["attributes"].is_object())
    return bad("the primitive has no attributes");
  // The README's "Restrictions on geometry type".
  const int mode =
      prim.contains("mode") && prim["mode"].is_number_integer() ? prim["mode"].get<int>() : 4;
  if (mode != 4 && mode != 5)
    return bad(
        strprintf("mode %d: Draco primitives are TRIANGLES (4) or TRIANGLE_STRIP (5)", mode));

  // Declared counts first: the budget is charged before anything decodes.
  auto accessor_of = [&](const json& slot, uint64_t* count) -> const json* {
    if (!slot.is_number_unsigned() || slot.get<uint64_t>() >= accessors.size()) return nullptr;
    const json& a = accessors[slot.get<size_t>()];
    if (!a.is_object() || !get_uint(a, "count", count)) return nullptr;
    return &a;
  };
  uint64_t declared = 0;
  for (const auto& [semantic, id] : ext["attributes"].items()) {
    // "attributes": the extension's attributes are a subset of the primitive's.
    if (!prim["attributes"].contains(semantic))
      return bad("attribute " + semantic + " is not an attribute of the primitive");
    if (!id.is_number_unsigned()) return bad("attribute " + semantic + ": id is not an integer");
    uint64_t count = 0;
    if (!accessor_of(prim["attributes"][semantic], &count))
      return bad("attribute " + semantic + ": no valid accessor");
    declared += count;
  }
  uint64_t index_count = 0;
  if (prim.contains("indices") && !accessor_of(prim["indices"], &index_count))
    return bad("indices: no valid accessor");
  LUXEL_RETURN_IF_ERROR(charge(declared + index_count, budget, what));
  // Draco's decoded mesh, the converted accessor data and its copy in the
  // .glb: up to 16 bytes per attribute element (VEC4 of floats) and 4 per
  // index, three times.
  LUXEL_RETURN_IF_ERROR(charge_bytes(
      bytes,
      detail::mul_sat(
          detail::add_sat(detail::mul_sat(declared, 16), detail::mul_sat(index_count, 4)), 3),
      what + strprintf(": %llu attribute elements, %llu indices",
                       static_cast<unsigned long long>(declared),
                       static_cast<unsigned long long>(index_count))));

  const json& view = doc->json["bufferViews"][view_index];
  uint64_t offset = 0, length = 0;
  get_uint(view, "byteOffset", &offset);
  if (!get_uint(view, "byteLength", &length) || offset > doc->bin.size() ||
      length > doc->bin.size() - offset)
    return bad(strprintf("bufferView %llu runs past its buffer",
                         static_cast<unsigned long long>(view_index)));
  draco::DecoderBuffer buffer;
  buffer.Init(reinterpret_cast<const char*>(doc->bin.data() + offset), length);
  draco::Decoder decoder;
  auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
  if (!decoded.ok())
    return bad(
        strprintf("the Draco bitstream in bufferView %llu does not decode (%s): corrupt "
                  "or truncated",
                  static_cast<unsigned long long>(view_index), decoded.status().error_msg()));
  const std::unique_ptr<draco::Mesh> dm = std::move(decoded).value();
  const size_t points = dm->num_points();
  const size_t faces = dm->num_faces();

  for (const auto& [semantic, id] : ext["attributes"].items()) {
    json& slot = prim["attributes"][semantic];
    const json& old = accessors[slot.get<size_t>()];
    const std::string who =
        "attribute " + semantic + strprintf(" (accessor %zu)", slot.get<size_t>());
    const draco::PointAttribute* attr = dm->GetAttributeByUniqueId(id.get<uint32_t>());
    if (attr == nullptr)
      return bad(strprintf("%s: the Draco data has no attribute with id %u", who.c_str(),
                           id.get<uint32_t>()));
    // The README's "accessors": the accessor must match the decoded data.
    if (old.value("count", uint64_t{0}) != points)
      return bad(strprintf("%s declares count %llu, the Draco data decodes to %zu vertices",
                           who.c_str(), static_cast<unsigned long long>(old.value("count", 0ull)),
                           points));
    const int comps = gltf_components(old.value("type", std::string()));
    if (comps != attr->num_components())
      return bad(strprintf("%s: type %s has %d components, the Draco attribute %d", who.c_str(),
                           old.value("type", std::string()).c_str(), comps,
                           attr->num_components()));
    Bytes data;
    std::vector<double> lo, hi;
    bool ok = false;
    switch (old.value("componentType", 0)) {
      case 5120:
        ok = convert_attribute<int8_t>(*dm, *attr, comps, &data, &lo, &hi);
        break;
      case 5121:
        ok = convert_attribute<uint8_t>(*dm, *attr, comps, &data, &lo, &hi);
        break;
      case 5122:
        ok = convert_attribute<int16_t>(*dm, *attr, comps, &data, &lo, &hi);
        break;
      case 5123:
        ok = convert_attribute<uint16_t>(*dm, *attr, comps, &data, &lo, &hi);
        break;
      case 5125:
        ok = convert_attribute<uint32_t>(*dm, *attr, comps, &data, &lo, &hi);
        break;
      case 5126:
        ok = convert_attribute<float>(*dm, *attr, comps, &data, &lo, &hi);
        break;
      default:
        return bad(who + ": unknown componentType");
    }
    if (!ok) return bad(who + ": a decoded value does not fit the accessor's componentType");
    set_accessor(doc, target_accessor(doc, ctx, &slot), data, kArrayBuffer, points, lo, hi);
  }

  // Faces as a triangle list, in the index accessor's component type (or
  // a new unsigned int accessor when the primitive had no indices).
  if (mode == 4 && prim.contains("indices") && index_count != 3 * faces)
    return bad(
        strprintf("indices (accessor %zu) declares count %llu, the Draco data decodes to "
                  "%zu triangles (%zu indices)",
                  prim["indices"].get<size_t>(), static_cast<unsigned long long>(index_count),
                  faces, 3 * faces));
  int ctype = 5125;
  if (prim.contains("indices"))
    ctype = accessors[prim["indices"].get<size_t>()].value("componentType", 0);
  const uint64_t max_index = ctype == 5121 ? 0xFFu : ctype == 5123 ? 0xFFFFu : 0xFFFFFFFFu;
  if (ctype != 5121 && ctype != 5123 && ctype != 5125)
    return bad("indices: componentType is not an unsigned integer type");
  if (points > 0 && points - 1 > max_index)
    return bad(strprintf("%zu vertices do not fit the indices' componentType %d", points, ctype));
  Bytes data;
  data.reserve(3 * faces * static_cast<size_t>(gltf_component_bytes(ctype)));
  for (draco::FaceIndex f(0); f < dm->num_faces(); ++f) {
    for (const draco::PointIndex& v : dm->face(f)) {
      const uint32_t i = v.value();
      if (ctype == 5121) put(&data, static_cast<uint8_t>(i));
      if (ctype == 5123) put(&data, static_cast<uint16_t>(i));
      if (ctype == 5125) put(&data, i);
    }
  }
  if (!prim.contains("indices")) {
    doc->json["accessors"].push_back({{"componentType", 5125}, {"type", "SCALAR"}, {"count", 0}});
    prim["indices"] = doc->json["accessors"].size() - 1;
    ctx->rewritten[static_cast<int>(doc->json["accessors"].size()) - 1] = true;
  }
  set_accessor(doc, target_accessor(doc, ctx, &prim["indices"]), data, kElementArrayBuffer,
               3 * faces, {}, {});
  if (mode == 5) prim["mode"] = 4;
  erase_extension(&prim, kDracoExtension);
  return Status::ok();
}

void drop_from_list(json* doc, const char* list, const char* name) {
  auto it = doc->find(list);
  if (it == doc->end() || !it->is_array()) return;
  json kept = json::array();
  for (const json& e : *it)
    if (!(e.is_string() && e.get<std::string>() == name)) kept.push_back(e);
  if (kept.empty()) {
    doc->erase(list);
  } else {
    *it = kept;
  }
}

}  // namespace

bool uses_compressed_geometry(const json& doc) {
  for (const char* list : {"buffers", "bufferViews"}) {
    if (!doc.contains(list) || !doc[list].is_array()) continue;
    for (const json& o : doc[list])
      if (has_extension(o, kMeshoptExtension)) return true;
  }
  if (!doc.contains("meshes") || !doc["meshes"].is_array()) return false;
  for (const json& mesh : doc["meshes"]) {
    if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array())
      continue;
    for (const json& prim : mesh["primitives"])
      if (has_extension(prim, kDracoExtension)) return true;
  }
  return false;
}

Status decompress_geometry(GltfDocument* doc, uint64_t max_elements, detail::ImportBudget* bytes) {
  json& j = doc->json;
  uint64_t budget = max_elements;
  for (size_t v = 0; v < j["bufferViews"].size(); ++v)
    if (has_extension(j["bufferViews"][v], kMeshoptExtension))
      LUXEL_RETURN_IF_ERROR(decode_meshopt_view(doc, v, &budget, bytes));
  if (j.contains("buffers") && j["buffers"].is_array())
    for (json& b : j["buffers"])
      if (has_extension(b, kMeshoptExtension)) erase_extension(&b, kMeshoptExtension);

  DracoContext ctx;
  if (j.contains("meshes") && j["meshes"].is_array()) {
    for (size_t m = 0; m < j["meshes"].size(); ++m) {
      json& mesh = j["meshes"][m];
      if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array())
        continue;
      for (size_t p = 0; p < mesh["primitives"].size(); ++p)
        if (has_extension(mesh["primitives"][p], kDracoExtension))
          LUXEL_RETURN_IF_ERROR(decode_draco_primitive(doc, m, p, &ctx, &budget, bytes));
    }
  }
  // Nothing uses either extension any more (every use was decoded above).
  for (const char* list : {"extensionsUsed", "extensionsRequired"}) {
    drop_from_list(&j, list, kDracoExtension);
    drop_from_list(&j, list, kMeshoptExtension);
  }
  return Status::ok();
}

}  // namespace luxel::scene
