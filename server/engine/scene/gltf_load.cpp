// See gltf_load.h. Order: container (GLB chunks) -> JSON syntax and depth ->
// references tinygltf would follow unchecked -> external files -> tinygltf.
#include "scene/gltf_load.h"

#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>

#include "common/uri.h"

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

struct DepthExceeded {};

Result<json> parse_json(std::string_view text, const std::string& name) {
  try {
    json::parser_callback_t limit_depth = [](int depth, json::parse_event_t, json&) {
      if (depth > kMaxJsonDepth) throw DepthExceeded{};
      return true;
    };
    json doc = json::parse(text.begin(), text.end(), limit_depth);
    if (!doc.is_object())
      return invalid_argument(strprintf("'%s': the glTF JSON is not an object", name.c_str()));
    return doc;
  } catch (const DepthExceeded&) {
    return invalid_argument(
        strprintf("'%s': JSON nested deeper than %d levels", name.c_str(), kMaxJsonDepth));
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

// Bytes a base64 data URI decodes to (tinygltf accepts only base64 payloads).
uint64_t data_uri_size(const std::string& uri) {
  const size_t comma = uri.find(',');
  if (comma == std::string::npos) return 0;
  uint64_t n = uri.size() - comma - 1;
  uint64_t pad = 0;
  for (size_t i = uri.size(); i > comma + 1 && uri[i - 1] == '=' && pad < 2; --i) ++pad;
  return n / 4 * 3 - std::min<uint64_t>(pad, n / 4 * 3);
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

Status check_buffers(const json& doc, const Container& c, const std::string& base_dir,
                     std::vector<uint64_t>* sizes) {
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
    const std::string uri = get_string(b, "uri");
    uint64_t available = 0;
    if (uri.empty()) {
      if (c.glb.empty()) return invalid_argument(what + ": no uri (only a .glb may omit it)");
      if (i != 0)
        return invalid_argument(what +
                                ": no uri (only buffer 0 of a .glb may refer to the BIN chunk)");
      if (!c.has_bin) return data_loss(what + ": refers to the BIN chunk, but the .glb has none");
      available = c.bin_size;
    } else if (is_data_uri(uri)) {
      available = data_uri_size(uri);
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
    if (!uri.empty() && !is_data_uri(uri)) {
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
                  tinygltf::Model* model) {
  if (bytes.size() > 0xFFFFFFF0u) {
    return resource_exhausted(
        strprintf("'%s': %zu bytes, glTF files are limited to 4 GiB", name.c_str(), bytes.size()));
  }
  Container c;
  LUXEL_RETURN_IF_ERROR(parse_container(bytes, name, &c));
  auto doc = parse_json(c.json, name);
  if (!doc) return doc.status();
  std::vector<uint64_t> buffer_sizes;
  LUXEL_RETURN_IF_ERROR(check_buffers(*doc, c, base_dir, &buffer_sizes));
  LUXEL_RETURN_IF_ERROR(check_images(*doc, base_dir, buffer_sizes));

  FsContext fsc{!base_dir.empty()};
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(&keep_encoded_image, nullptr);
  loader.SetFsCallbacks(tinygltf::FsCallbacks{&fs_exists, &fs_expand, &fs_read, &fs_write, &fsc});
  std::string err, warn;
  bool ok = false;
  try {
    if (c.glb.empty()) {
      ok = loader.LoadASCIIFromString(model, &err, &warn, c.json.data(),
                                      static_cast<unsigned>(c.json.size()), base_dir,
                                      tinygltf::NO_REQUIRE);
    } else {
      ok = loader.LoadBinaryFromMemory(
          model, &err, &warn, reinterpret_cast<const unsigned char*>(c.glb.data()),
          static_cast<unsigned>(c.glb.size()), base_dir, tinygltf::NO_REQUIRE);
    }
  } catch (const std::exception& e) {
    return invalid_argument(strprintf("'%s': malformed glTF: %s", name.c_str(), e.what()));
  }
  if (!ok) return invalid_argument(strprintf("'%s': %s", name.c_str(), trim(err).c_str()));
  return Status::ok();
}

}  // namespace luxel::scene::detail
