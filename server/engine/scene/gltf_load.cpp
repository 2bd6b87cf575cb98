// See gltf_load.h. Order: container (GLB chunks) -> JSON syntax and depth ->
// references tinygltf would follow unchecked -> external files -> tinygltf.
// Over 500 lines: every check a file passes before tinygltf sees it is here, in
// the order a file is read, so the rules against hostile input have one place.
#include "scene/gltf_load.h"

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <tuple>

#include "common/uri.h"
#include "scene/gltf_decompress.h"
#include "scene/gltf_document.h"

namespace luxel::scene::detail {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr uint32_t kChunkJson = 0x4E4F534A;
constexpr uint32_t kChunkBin = 0x004E4942;

uint32_t read_u32(const char* p) {
  uint32_t v;
  std::memcpy(&v, p, 4);  // glb is little-endian, as is every supported host
  return v;
}

struct Container {
  std::string_view json;
  std::string_view glb;  // the whole glb as declared by its header; empty for .gltf
  uint64_t bin_size = 0;
  bool has_bin = false;
};

// Validates the GLB header and chunk table completely, so that tinygltf (which
// reads the BIN chunk header without checking it fits) only sees consistent
// input.
Status parse_container(std::string_view bytes, const std::string& name, Container* out) {
  if (bytes.size() < 4 || read_u32(bytes.data()) != kGlbMagic) {
    out->json = bytes;
    return Status::ok();
  }
  if (bytes.size() < 20) {
    return data_loss(strprintf("'%s': truncated .glb: %zu bytes, the header alone needs 20",
                               name.c_str(), bytes.size()));
  }
  const uint32_t version = read_u32(bytes.data() + 4);
  const uint64_t length = read_u32(bytes.data() + 8);
  const uint64_t json_length = read_u32(bytes.data() + 12);
  if (version == 1) {
    return invalid_argument(
        strprintf("'%s': .glb version 1: glTF 1.0 is not supported; convert the file to glTF 2.0",
                  name.c_str()));
  }
  if (version != 2) {
    return invalid_argument(
        strprintf("'%s': .glb version %u, only 2 is supported", name.c_str(), version));
  }
  if (length > bytes.size()) {
    return data_loss(
        strprintf("'%s': truncated .glb: the header declares %llu bytes, the data has %zu",
                  name.c_str(), static_cast<unsigned long long>(length), bytes.size()));
  }
  if (read_u32(bytes.data() + 16) != kChunkJson) {
    return invalid_argument(strprintf("'%s': .glb: the first chunk is not JSON", name.c_str()));
  }
  if (20 + json_length > length) {
    return data_loss(strprintf(
        "'%s': truncated .glb: the JSON chunk (%llu bytes) runs past the end (%llu bytes)",
        name.c_str(), static_cast<unsigned long long>(json_length),
        static_cast<unsigned long long>(length)));
  }
  if (json_length == 0 || json_length % 4 != 0) {
    return invalid_argument(
        strprintf("'%s': .glb: JSON chunk length %llu is not a positive multiple of 4",
                  name.c_str(), static_cast<unsigned long long>(json_length)));
  }
  out->glb = bytes.substr(0, length);
  out->json = bytes.substr(20, json_length);
  const uint64_t bin_at = 20 + json_length;
  if (bin_at == length) return Status::ok();
  if (bin_at + 8 > length) {
    return data_loss(
        strprintf("'%s': truncated .glb: %llu bytes after the JSON chunk, a chunk header needs 8",
                  name.c_str(), static_cast<unsigned long long>(length - bin_at)));
  }
  const uint64_t bin_length = read_u32(bytes.data() + bin_at);
  if (read_u32(bytes.data() + bin_at + 4) != kChunkBin) {
    return invalid_argument(strprintf("'%s': .glb: the second chunk is not BIN", name.c_str()));
  }
  if (bin_at + 8 + bin_length > length) {
    return data_loss(
        strprintf("'%s': truncated .glb: the BIN chunk declares %llu bytes, %llu remain",
                  name.c_str(), static_cast<unsigned long long>(bin_length),
                  static_cast<unsigned long long>(length - bin_at - 8)));
  }
  if (bin_length == 0 || bin_length % 4 != 0) {
    return invalid_argument(
        strprintf("'%s': .glb: BIN chunk length %llu is not a positive multiple of 4", name.c_str(),
                  static_cast<unsigned long long>(bin_length)));
  }
  out->has_bin = true;
  out->bin_size = bin_length;
  return Status::ok();
}

// A SAX pass that only counts nesting: the parse below builds the document
// without a callback. (A callback makes nlohmann 3.11.2's DOM builder scan the
// parent container for discarded values at the end of every object, which is
// quadratic in the number of objects of one array: a 100,000-node glTF took
// 27 s to parse that way, docs/performance.md "Scene import".)
class DepthCheck : public json::json_sax_t {
 public:
  bool exceeded() const { return exceeded_; }

  bool null() override { return true; }
  bool boolean(bool) override { return true; }
  bool number_integer(number_integer_t) override { return true; }
  bool number_unsigned(number_unsigned_t) override { return true; }
  bool number_float(number_float_t, const string_t&) override { return true; }
  bool string(string_t&) override { return true; }
  bool binary(binary_t&) override { return true; }
  bool key(string_t&) override { return true; }
  bool start_object(std::size_t) override { return enter(); }
  bool end_object() override { return leave(); }
  bool start_array(std::size_t) override { return enter(); }
  bool end_array() override { return leave(); }
  // Syntax errors are reported by the parse that follows, with its message.
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) override {
    return false;
  }

 private:
  bool enter() {
    exceeded_ = ++depth_ > kMaxJsonDepth;
    return !exceeded_;
  }
  bool leave() {
    --depth_;
    return true;
  }
  int depth_ = 0;
  bool exceeded_ = false;
};

Result<json> parse_json(std::string_view text, const std::string& name) {
  try {
    DepthCheck depth;
    json::sax_parse(text.begin(), text.end(), &depth);
    if (depth.exceeded())
      return invalid_argument(
          strprintf("'%s': JSON nested deeper than %d levels", name.c_str(), kMaxJsonDepth));
    json doc = json::parse(text.begin(), text.end());
    if (!doc.is_object())
      return invalid_argument(strprintf("'%s': the glTF JSON is not an object", name.c_str()));
    return doc;
  } catch (const std::exception& e) {
    return invalid_argument(strprintf("'%s': invalid JSON: %s", name.c_str(), e.what()));
  }
}

// A non-negative integer member, or nullopt when absent or of another type
// (tinygltf reports those itself).
std::optional<uint64_t> get_uint(const json& o, const char* key) {
  auto it = o.find(key);
  if (it == o.end() || !it->is_number_unsigned()) return std::nullopt;
  return it->get<uint64_t>();
}

std::string get_string(const json& o, const char* key) {
  auto it = o.find(key);
  return it != o.end() && it->is_string() ? it->get<std::string>() : std::string();
}

bool is_data_uri(const std::string& uri) {
  return uri.rfind("data:", 0) == 0;
}

bool is_base64_char(char ch) {
  return (ch >= 'A' && ch <= 'Z') || (ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9') ||
         ch == '+' || ch == '/';
}

// Checks a data URI (RFC 2397, base64 payload as glTF 2.0 §3.6.1.1 requires)
// and returns the number of bytes it decodes to. The media types are the ones
// tinygltf decodes; any other data URI would be taken for a file name by
// tinygltf and reported as a missing file.
Result<uint64_t> check_data_uri(const std::string& uri, bool image, const std::string& what) {
  auto bad = [&](const std::string& why) {
    return invalid_argument(strprintf("%s: malformed data URI (%s)", what.c_str(), why.c_str()));
  };
  const size_t comma = uri.find(',');
  if (comma == std::string::npos) return bad("no ',' between the header and the data");
  const std::string header = uri.substr(5, comma - 5);  // after "data:"
  const std::string suffix = ";base64";
  if (header.size() < suffix.size() ||
      header.compare(header.size() - suffix.size(), suffix.size(), suffix) != 0) {
    return bad("'data:" + header + ",' is not base64; glTF data URIs must be base64");
  }
  const std::string media = header.substr(0, header.size() - suffix.size());
  static const char* const kBufferTypes[] = {"application/octet-stream", "application/gltf-buffer"};
  static const char* const kImageTypes[] = {"image/png", "image/jpeg", "image/bmp", "image/gif"};
  bool known = false;
  for (const char* t : kBufferTypes) known = known || (!image && media == t);
  for (const char* t : kImageTypes) known = known || (image && media == t);
  if (!known) {
    return invalid_argument(strprintf(
        "%s: data URI media type '%s' is not supported (%s)", what.c_str(), media.c_str(),
        image ? "image/png or image/jpeg" : "application/octet-stream or application/gltf-buffer"));
  }
  const size_t begin = comma + 1;
  size_t end = uri.size();
  uint64_t pad = 0;
  while (end > begin && uri[end - 1] == '=' && pad < 2) {
    --end;
    ++pad;
  }
  for (size_t i = begin; i < end; ++i) {
    if (!is_base64_char(uri[i]))
      return bad(strprintf("character %zu of the data is not base64", i - begin));
  }
  const uint64_t n = end - begin;
  if (n % 4 == 1 || (pad > 0 && (n + pad) % 4 != 0)) return bad("truncated base64 data");
  return n / 4 * 3 + (n % 4 == 0 ? 0 : n % 4 - 1);
}

// Resolves an external URI for `what` ("buffer 0", "image 3 'wood'").
Result<fs::path> resolve_external(const std::string& uri, const std::string& base_dir,
                                  const std::string& what) {
  if (base_dir.empty()) {
    return not_found(
        strprintf("%s: external file '%s' cannot be read: the scene was given without its folder "
                  "(embed the data or upload the file with it)",
                  what.c_str(), uri.c_str()));
  }
  // The uri is a URI reference: "%20" is a space in the file name.
  auto decoded = percent_decode_uri(uri);
  if (!decoded) return invalid_argument(what + ": " + decoded.status().message());
  const std::string& path = decoded.value();
  const fs::path rel(path);
  bool escapes = rel.is_absolute() || path.find('\0') != std::string::npos;
  for (const auto& part : rel) escapes = escapes || part == "..";
  if (escapes) {
    return invalid_argument(strprintf(
        "%s: uri '%s' must be a relative path inside the scene folder", what.c_str(), uri.c_str()));
  }
  fs::path full = fs::path(base_dir) / rel;
  std::error_code ec;
  if (!fs::is_regular_file(full, ec)) {
    return not_found(strprintf("%s: file '%s' not found (looked for '%s')", what.c_str(),
                               uri.c_str(), full.string().c_str()));
  }
  return full;
}

std::string describe(const char* kind, size_t i, const json& o) {
  const std::string n = get_string(o, "name");
  return n.empty() ? strprintf("%s %zu", kind, i) : strprintf("%s %zu '%s'", kind, i, n.c_str());
}

bool is_meshopt_fallback(const json& buffer) {
  auto ext = buffer.find("extensions");
  if (ext == buffer.end() || !ext->is_object()) return false;
  auto m = ext->find(kMeshoptExtension);
  if (m == ext->end() || !m->is_object()) return false;
  auto f = m->find("fallback");
  return f != m->end() && f->is_boolean() && f->get<bool>();
}

Status check_buffers(const json& doc, const Container& c, const std::string& base_dir,
                     std::vector<uint64_t>* sizes, std::vector<size_t>* uriless) {
  auto it = doc.find("buffers");
  if (it == doc.end() || !it->is_array()) return Status::ok();  // tinygltf reports a wrong type
  for (size_t i = 0; i < it->size(); ++i) {
    const json& b = (*it)[i];
    if (!b.is_object()) return invalid_argument(strprintf("buffer %zu is not a JSON object", i));
    const std::string what = describe("buffer", i, b);
    const auto length = get_uint(b, "byteLength");
    if (!length)
      return invalid_argument(what + ": byteLength is missing or not a non-negative integer");
    sizes->push_back(*length);
    // EXT_meshopt_compression "Fallback buffers" are not read (their views
    // are decoded from compressed data, scene/gltf_decompress.h); in a .glb
    // one without uri has index 1 or above and no data.
    if (is_meshopt_fallback(b)) continue;
    const std::string uri = get_string(b, "uri");
    uint64_t available = 0;
    if (uri.empty()) {
      // A .gltf buffer without data is valid as long as nothing reads it
      // (glTF 2.0 §5.10: uri is optional); a read reports it (accessor.cpp).
      if (c.glb.empty()) {
        uriless->push_back(i);
        continue;
      }
      if (i != 0)
        return invalid_argument(what +
                                ": no uri (only buffer 0 of a .glb may refer to the BIN chunk)");
      if (!c.has_bin) return data_loss(what + ": refers to the BIN chunk, but the .glb has none");
      available = c.bin_size;
    } else if (is_data_uri(uri)) {
      auto size = check_data_uri(uri, false, what);
      if (!size) return size.status();
      available = *size;
    } else {
      auto path = resolve_external(uri, base_dir, what);
      if (!path) return path.status();
      std::error_code ec;
      available = fs::file_size(*path, ec);
      if (ec)
        return not_found(
            strprintf("%s: cannot read '%s': %s", what.c_str(), uri.c_str(), ec.message().c_str()));
    }
    if (available < *length) {
      return data_loss(strprintf("%s: byteLength is %llu but the data holds only %llu bytes",
                                 what.c_str(), static_cast<unsigned long long>(*length),
                                 static_cast<unsigned long long>(available)));
    }
  }
  return Status::ok();
}

// Images: external files must exist; a buffer view image must lie inside its
// buffer (tinygltf takes a pointer into the buffer before anyone checks).
Status check_images(const json& doc, const std::string& base_dir,
                    const std::vector<uint64_t>& buffer_sizes) {
  auto it = doc.find("images");
  if (it == doc.end() || !it->is_array()) return Status::ok();
  auto views = doc.find("bufferViews");
  for (size_t i = 0; i < it->size(); ++i) {
    const json& img = (*it)[i];
    if (!img.is_object()) return invalid_argument(strprintf("image %zu is not a JSON object", i));
    const std::string what = describe("image", i, img);
    const std::string uri = get_string(img, "uri");
    if (is_data_uri(uri)) {
      auto size = check_data_uri(uri, true, what);
      if (!size) return size.status();
    } else if (!uri.empty()) {
      auto path = resolve_external(uri, base_dir, what);
      if (!path) return path.status();
    }
    if (img.find("bufferView") == img.end()) continue;
    const auto view = get_uint(img, "bufferView");
    if (!view || views == doc.end() || !views->is_array() || *view >= views->size() ||
        !(*views)[*view].is_object()) {
      return invalid_argument(what + ": bufferView is not a valid bufferView index");
    }
    const json& bv = (*views)[*view];
    const auto buffer = get_uint(bv, "buffer");
    const uint64_t offset = get_uint(bv, "byteOffset").value_or(0);
    const auto length = get_uint(bv, "byteLength");
    if (!buffer || *buffer >= buffer_sizes.size() || !length) {
      return invalid_argument(strprintf("%s: bufferView %llu has no valid buffer or byteLength",
                                        what.c_str(), static_cast<unsigned long long>(*view)));
    }
    const uint64_t size = buffer_sizes[*buffer];
    if (offset > size || *length > size - offset) {
      return data_loss(strprintf(
          "%s: bufferView %llu (byteOffset %llu, byteLength %llu) overruns buffer %llu "
          "(%llu bytes)",
          what.c_str(), static_cast<unsigned long long>(*view),
          static_cast<unsigned long long>(offset), static_cast<unsigned long long>(*length),
          static_cast<unsigned long long>(*buffer), static_cast<unsigned long long>(size)));
    }
  }
  return Status::ok();
}

// glTF 2.0 §3.2 (asset): a file whose minVersion is newer than 2.0, or whose
// major version is not 2, must not be loaded. glTF 1.0 files parse as JSON and
// tinygltf would read them as an empty 2.0 scene, so they are named.
Status check_asset(const json& doc) {
  auto it = doc.find("asset");
  if (it == doc.end() || !it->is_object())
    return invalid_argument("asset is missing (every glTF file has asset.version)");
  auto parse = [](const std::string& v, int* major, int* minor) {
    return std::sscanf(v.c_str(), "%d.%d", major, minor) == 2 && *major >= 0 && *minor >= 0;
  };
  const std::string version = get_string(*it, "version");
  int major = 0, minor = 0;
  if (!parse(version, &major, &minor))
    return invalid_argument("asset.version '" + version + "' is not of the form major.minor");
  if (major == 1) {
    return invalid_argument("asset.version is " + version +
                            ": glTF 1.0 is not supported; convert the file to glTF 2.0");
  }
  if (major != 2) {
    return invalid_argument("asset.version is " + version + ": only glTF 2.x is supported");
  }
  if (it->contains("minVersion")) {
    const std::string min_version = get_string(*it, "minVersion");
    if (!parse(min_version, &major, &minor))
      return invalid_argument("asset.minVersion '" + min_version +
                              "' is not of the form major.minor");
    if (major != 2 || minor > 0) {
      return invalid_argument("asset.minVersion is " + min_version +
                              ": the file needs a newer glTF than 2.0, which is what Luxel reads");
    }
  }
  return Status::ok();
}

// False with the reason when `view` has a byteStride outside glTF 2.0 §5.11's
// range (4 to 252, a multiple of 4); absent is valid (tightly packed).
bool byte_stride_ok(const json& view, std::string* why) {
  if (!view.is_object()) return true;
  auto s = view.find("byteStride");
  if (s == view.end()) return true;
  if (s->is_number_unsigned()) {
    const uint64_t v = s->get<uint64_t>();
    if (v >= 4 && v <= 252 && v % 4 == 0) return true;
  }
  *why = "byteStride " + s->dump() + " is not valid (glTF allows 4 to 252, a multiple of 4)";
  return false;
}

// What tinygltf would refuse with a message that names no object: accessor
// componentType and type (glTF 2.0 §5.1).
Status check_accessors(const json& doc) {
  auto it = doc.find("accessors");
  if (it == doc.end() || !it->is_array()) return Status::ok();
  const auto views = doc.find("bufferViews");
  for (size_t i = 0; i < it->size(); ++i) {
    const json& a = (*it)[i];
    if (!a.is_object()) return invalid_argument(strprintf("accessor %zu is not a JSON object", i));
    const std::string what = describe("accessor", i, a);
    const auto ct = get_uint(a, "componentType");
    if (!ct ||
        !(*ct == 5120 || *ct == 5121 || *ct == 5122 || *ct == 5123 || *ct == 5125 || *ct == 5126)) {
      auto v = a.find("componentType");
      return invalid_argument(
          strprintf("%s: componentType %s is not a glTF component type (5120-5123, 5125, 5126)",
                    what.c_str(), v == a.end() ? "(missing)" : v->dump().c_str()));
    }
    const std::string type = get_string(a, "type");
    static const char* const kTypes[] = {"SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4"};
    bool known = false;
    for (const char* t : kTypes) known = known || type == t;
    if (!known) {
      return invalid_argument(
          strprintf("%s: type '%s' is not a glTF accessor type", what.c_str(), type.c_str()));
    }
    if (!get_uint(a, "count"))
      return invalid_argument(what + ": count is missing or not a non-negative integer");
    // tinygltf reads an explicit byteStride 0 as "tightly packed", which the
    // schema forbids; named here through the accessor that reads the view.
    const auto view = get_uint(a, "bufferView");
    if (view && views != doc.end() && views->is_array() && *view < views->size()) {
      std::string why;
      if (!byte_stride_ok((*views)[*view], &why))
        return invalid_argument(strprintf("%s: bufferView %llu: %s", what.c_str(),
                                          static_cast<unsigned long long>(*view), why.c_str()));
    }
  }
  return Status::ok();
}

// glTF 2.0 §5.11 (bufferView.byteStride): when present, 4 to 252 and a
// multiple of 4. Views no accessor reads are checked here.
Status check_buffer_views(const json& doc) {
  auto it = doc.find("bufferViews");
  if (it == doc.end() || !it->is_array()) return Status::ok();
  for (size_t i = 0; i < it->size(); ++i) {
    std::string why;
    if (!byte_stride_ok((*it)[i], &why))
      return invalid_argument(describe("bufferView", i, (*it)[i]) + ": " + why);
  }
  return Status::ok();
}

// glTF 2.0 §5.24 (mesh.primitive.material): a non-negative index when
// present. tinygltf keeps a negative value, which would otherwise read as
// "no material".
Status check_meshes(const json& doc) {
  auto meshes = doc.find("meshes");
  if (meshes == doc.end() || !meshes->is_array()) return Status::ok();
  for (size_t m = 0; m < meshes->size(); ++m) {
    const json& mesh = (*meshes)[m];
    if (!mesh.is_object()) continue;
    auto prims = mesh.find("primitives");
    if (prims == mesh.end() || !prims->is_array()) continue;
    for (size_t p = 0; p < prims->size(); ++p) {
      const json& prim = (*prims)[p];
      if (!prim.is_object()) continue;
      auto mat = prim.find("material");
      if (mat == prim.end() || mat->is_number_unsigned()) continue;
      const std::string name = get_string(mesh, "name");
      const std::string what = name.empty() ? strprintf("mesh[%zu]", m)
                                            : strprintf("mesh '%s' (mesh[%zu])", name.c_str(), m);
      return invalid_argument(
          strprintf("%s primitive %zu: material %s is not a material index (a non-negative "
                    "integer)",
                    what.c_str(), p, mat->dump().c_str()));
    }
  }
  return Status::ok();
}

// Valid documents tinygltf 2.7 refuses, rewritten before it parses them and
// restored afterwards (see load_model):
//  - an index accessor without a bufferView (all zeros or sparse, glTF 2.0
//    §3.6.2; also KHR_draco_mesh_compression primitives): tinygltf insists
//    on a bufferView, so the primitive's `indices` is hidden from it;
//  - a .gltf buffer without uri (glTF 2.0 §5.10: uri is optional): tinygltf
//    reads a file named "", so the buffer is given a stand-in data URI
//    and its data is removed again after parsing.
struct Rewrites {
  std::vector<std::tuple<size_t, size_t, int>> hidden_indices;  // mesh, primitive, accessor
  // Per hidden index, the mesh's primitive count in the JSON: tinygltf skips
  // a primitive it cannot read (no "attributes"), after which (mesh,
  // primitive) no longer names the same primitive.
  std::vector<size_t> primitive_counts;
  std::vector<size_t> uriless_buffers;
  bool any() const { return !hidden_indices.empty() || !uriless_buffers.empty(); }
};

void hide_unviewed_indices(json* doc, Rewrites* rw) {
  auto accessors = doc->find("accessors");
  auto meshes = doc->find("meshes");
  if (accessors == doc->end() || !accessors->is_array() || meshes == doc->end() ||
      !meshes->is_array())
    return;
  for (size_t m = 0; m < meshes->size(); ++m) {
    json& mesh = (*meshes)[m];
    if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array())
      continue;
    json& prims = mesh["primitives"];
    for (size_t p = 0; p < prims.size(); ++p) {
      json& prim = prims[p];
      if (!prim.is_object()) continue;
      const auto idx = get_uint(prim, "indices");
      if (!idx || *idx >= accessors->size() || !(*accessors)[*idx].is_object() ||
          (*accessors)[*idx].contains("bufferView"))
        continue;
      rw->hidden_indices.emplace_back(m, p, static_cast<int>(*idx));
      rw->primitive_counts.push_back(prims.size());
      prim.erase("indices");
    }
  }
}

void give_uriless_buffers_empty_data(json* doc, Rewrites* rw) {
  for (size_t i : rw->uriless_buffers) {
    json& b = (*doc)["buffers"][i];
    b["uri"] = "data:application/octet-stream;base64,AA==";  // tinygltf refuses empty data
    b["byteLength"] = 1;
  }
}

void put_u32(std::string* out, uint32_t v) {
  char b[4];
  std::memcpy(b, &v, 4);
  out->append(b, 4);
}

// A .glb with a new JSON chunk and the original BIN chunk.
std::string rebuild_glb(const Container& c, const std::string& json_text) {
  std::string chunk = json_text;
  while (chunk.size() % 4 != 0) chunk.push_back(' ');
  const size_t bin_at = 20 + c.json.size();
  const std::string_view rest = c.glb.substr(bin_at);  // BIN chunk with its header, if any
  std::string out;
  put_u32(&out, kGlbMagic);
  put_u32(&out, 2);
  put_u32(&out, static_cast<uint32_t>(12 + 8 + chunk.size() + rest.size()));
  put_u32(&out, static_cast<uint32_t>(chunk.size()));
  put_u32(&out, kChunkJson);
  out += chunk;
  out.append(rest.data(), rest.size());
  return out;
}

// A .glb whose magic is wrong is read as JSON; say what it is not.
bool looks_like_json(std::string_view bytes) {
  if (bytes.substr(0, 3) == "\xEF\xBB\xBF") bytes.remove_prefix(3);  // UTF-8 BOM
  for (char ch : bytes) {
    if (ch == ' ' || ch == '\t' || ch == '\n' || ch == '\r') continue;
    return ch == '{' || ch == '[';  // '[': parse_json names what is wrong
  }
  return false;
}

// tinygltf callbacks. Encoded image bytes are kept as they are (decoded later
// with limits); images in buffer views are read later through checked views,
// so the pointer tinygltf passes for them is never dereferenced.
bool keep_encoded_image(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                        const unsigned char* bytes, int size, void*) {
  if (image->bufferView >= 0) return true;
  if (bytes != nullptr && size > 0) image->image.assign(bytes, bytes + size);
  image->as_is = true;
  return true;
}

struct FsContext {
  bool allow = false;
};

bool fs_exists(const std::string& path, void* user) {
  if (!static_cast<FsContext*>(user)->allow) return false;
  std::error_code ec;
  return fs::is_regular_file(path, ec);
}

// No shell-style expansion (the default once used wordexp).
std::string fs_expand(const std::string& path, void*) {
  return path;
}

bool fs_read(std::vector<unsigned char>* out, std::string* err, const std::string& path,
             void* user) {
  if (!static_cast<FsContext*>(user)->allow) return false;
  std::ifstream f(path, std::ios::binary);
  if (!f) {
    if (err) *err += "cannot open " + path + "\n";
    return false;
  }
  out->assign(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
  return true;
}

bool fs_write(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err += "writing is not supported\n";
  return false;
}

std::string trim(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  for (auto& ch : s) ch = ch == '\n' ? ';' : ch;
  return s;
}

}  // namespace

Status load_model(std::string_view bytes, const std::string& base_dir, const std::string& name,
                  ImportBudget* budget, tinygltf::Model* model) {
  if (bytes.size() > 0xFFFFFFF0u) {
    return resource_exhausted(
        strprintf("'%s': %zu bytes, glTF files are limited to 4 GiB", name.c_str(), bytes.size()));
  }
  Container c;
  LUXEL_RETURN_IF_ERROR(parse_container(bytes, name, &c));
  if (c.glb.empty() && !looks_like_json(c.json)) {
    const std::string_view m = bytes.substr(0, 4);
    std::string shown;
    for (char ch : m)
      shown += ch >= 0x20 && ch < 0x7f ? std::string(1, ch)
                                       : strprintf("\\x%02x", static_cast<unsigned char>(ch));
    return invalid_argument(
        strprintf("'%s': not a glTF file: not a GLB (bad magic '%s', a .glb starts with 'glTF') "
                  "and not glTF JSON (which starts with '{')",
                  name.c_str(), shown.c_str()));
  }
  auto doc = parse_json(c.json, name);
  if (!doc) return doc.status();
  LUXEL_RETURN_IF_ERROR(check_asset(*doc));
  LUXEL_RETURN_IF_ERROR(check_accessors(*doc));
  LUXEL_RETURN_IF_ERROR(check_buffer_views(*doc));
  LUXEL_RETURN_IF_ERROR(check_meshes(*doc));
  std::vector<uint64_t> buffer_sizes;
  Rewrites rw;
  LUXEL_RETURN_IF_ERROR(check_buffers(*doc, c, base_dir, &buffer_sizes, &rw.uriless_buffers));
  LUXEL_RETURN_IF_ERROR(check_images(*doc, base_dir, buffer_sizes));
  if (uses_compressed_geometry(*doc)) {
    // Decoded at the JSON level (shared with the write-back of lightmap
    // UVs), then loaded as the plain .glb it becomes; the external files it
    // reads are the ones checked above.
    auto plain = read_gltf_document(bytes, base_dir);
    if (!plain) return plain.status();
    LUXEL_RETURN_IF_ERROR(decompress_geometry(&plain.value(), budget->elements_left, budget));
    if (uses_compressed_geometry(plain.value().json))
      return internal_error("compressed geometry remained after decoding");
    return load_model(write_glb(std::move(plain).value()), base_dir, name, budget, model);
  }
  hide_unviewed_indices(&*doc, &rw);
  give_uriless_buffers_empty_data(&*doc, &rw);
  std::string rewritten;
  if (rw.any()) {
    rewritten = doc->dump();
    if (!c.glb.empty()) rewritten = rebuild_glb(c, rewritten);
  }

  FsContext fsc{!base_dir.empty()};
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(&keep_encoded_image, nullptr);
  loader.SetFsCallbacks(tinygltf::FsCallbacks{&fs_exists, &fs_expand, &fs_read, &fs_write, &fsc});
  std::string err, warn;
  bool ok = false;
  try {
    const std::string_view json_text = rw.any() && c.glb.empty() ? rewritten : c.json;
    const std::string_view glb = rw.any() ? std::string_view(rewritten) : c.glb;
    if (c.glb.empty()) {
      ok = loader.LoadASCIIFromString(model, &err, &warn, json_text.data(),
                                      static_cast<unsigned>(json_text.size()), base_dir,
                                      tinygltf::NO_REQUIRE);
    } else {
      ok = loader.LoadBinaryFromMemory(
          model, &err, &warn, reinterpret_cast<const unsigned char*>(glb.data()),
          static_cast<unsigned>(glb.size()), base_dir, tinygltf::NO_REQUIRE);
    }
  } catch (const std::exception& e) {
    return invalid_argument(strprintf("'%s': malformed glTF: %s", name.c_str(), e.what()));
  }
  if (!ok) {
    err = trim(err);
    if (err.empty()) {
      // tinygltf returns false without a message when a property has the
      // wrong JSON type in some places.
      err =
          "malformed glTF: a property has the wrong type or a required one is missing "
          "(tinygltf gave no detail)";
    }
    return invalid_argument(strprintf("'%s': %s", name.c_str(), err.c_str()));
  }
  for (size_t k = 0; k < rw.hidden_indices.size(); ++k) {
    const auto& [m, p, accessor] = rw.hidden_indices[k];
    if (m >= model->meshes.size() || model->meshes[m].primitives.size() != rw.primitive_counts[k])
      return invalid_argument(
          strprintf("'%s': malformed glTF: mesh %zu has a primitive that could not be read (a "
                    "required property such as \"attributes\" is missing or has the wrong type)",
                    name.c_str(), m));
    model->meshes[m].primitives[p].indices = accessor;
  }
  for (size_t b : rw.uriless_buffers) {
    model->buffers[b].uri.clear();
    model->buffers[b].data.clear();
  }
  return Status::ok();
}

}  // namespace luxel::scene::detail
