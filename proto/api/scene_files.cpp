#include "api/scene_files.h"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <set>

#include "api/file_hash.h"
#include "common/scene_id.h"
#include "common/uri.h"

namespace luxel::cli::remote {
namespace {

namespace fs = std::filesystem;

std::string lower_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

// The JSON of a .gltf file, or the JSON chunk of a .glb (glTF 2.0 §4.4: a
// 12-byte header, then chunks of length, type, data; JSON comes first).
grpc::Status read_gltf_json(const std::string& path, bool glb, nlohmann::json& json) {
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof()) return {grpc::StatusCode::INTERNAL, "cannot read '" + path + "'"};
  std::string text = bytes;
  if (glb) {
    uint32_t chunk_length = 0, chunk_type = 0;
    if (bytes.size() < 20 || bytes.compare(0, 4, "glTF") != 0)
      return {grpc::StatusCode::INVALID_ARGUMENT, "'" + path + "' is not a binary glTF (.glb)"};
    std::memcpy(&chunk_length, bytes.data() + 12, 4);
    std::memcpy(&chunk_type, bytes.data() + 16, 4);
    if (chunk_type != 0x4E4F534Au || 20 + uint64_t{chunk_length} > bytes.size())
      return {grpc::StatusCode::INVALID_ARGUMENT,
              "'" + path + "': the first .glb chunk is not JSON"};
    text = bytes.substr(20, chunk_length);
  }
  json = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (json.is_discarded() || !json.is_object())
    return {grpc::StatusCode::INVALID_ARGUMENT, "'" + path + "' is not valid glTF JSON"};
  return grpc::Status::OK;
}

grpc::Status add_resources(const nlohmann::json& json, const char* array, const fs::path& dir,
                           std::set<std::string>& seen, std::vector<SceneFile>& out) {
  auto it = json.find(array);
  if (it == json.end() || !it->is_array()) return grpc::Status::OK;
  for (size_t i = 0; i < it->size(); ++i) {
    const auto& entry = (*it)[i];
    if (!entry.is_object() || !entry.contains("uri") || !entry["uri"].is_string()) continue;
    const std::string uri = entry["uri"].get<std::string>();
    if (uri.rfind("data:", 0) == 0 || !seen.insert(uri).second) continue;
    const std::string where = std::string(array) + "[" + std::to_string(i) + "].uri '" + uri + "'";
    if (uri.find("://") != std::string::npos || (!uri.empty() && uri[0] == '/'))
      return {grpc::StatusCode::INVALID_ARGUMENT,
              where + ": only relative file uris can be uploaded"};
    // glTF uris are RFC 3986 references: "%20" is a space in the file name.
    auto decoded = percent_decode_uri(uri);
    if (!decoded)
      return {grpc::StatusCode::INVALID_ARGUMENT,
              std::string(array) + "[" + std::to_string(i) + "]: " + decoded.status().message()};
    SceneFile f;
    f.uri = uri;
    f.path = (dir / decoded.value()).string();
    if (auto st = hash_file(f.path, f.size, f.sha256); !st.ok())
      return {st.error_code(), where + ": " + st.error_message()};
    out.push_back(std::move(f));
  }
  return grpc::Status::OK;
}

}  // namespace

grpc::Status collect_scene_files(const std::string& path, SceneFiles& out) {
  const std::string ext = lower_extension(path);
  if (ext != ".gltf" && ext != ".glb")
    return {grpc::StatusCode::INVALID_ARGUMENT,
            "'" + path + "' is not a glTF scene (expected a .gltf or .glb file)"};
  out = SceneFiles{};
  out.format = ext == ".glb" ? luxel::v1::SCENE_FORMAT_GLB : luxel::v1::SCENE_FORMAT_GLTF;
  out.main.path = path;
  if (auto st = hash_file(path, out.main.size, out.main.sha256); !st.ok()) return st;
  nlohmann::json json;
  if (auto st = read_gltf_json(path, ext == ".glb", json); !st.ok()) return st;
  const fs::path dir = fs::path(path).parent_path();
  std::set<std::string> seen;
  if (auto st = add_resources(json, "buffers", dir, seen, out.resources); !st.ok()) return st;
  return add_resources(json, "images", dir, seen, out.resources);
}

std::string scene_id(const SceneFiles& files) {
  std::vector<SceneIdResource> resources;
  for (const SceneFile& r : files.resources) resources.push_back({r.uri, r.size, r.sha256});
  return luxel::scene_id(files.main.sha256, std::move(resources));
}

luxel::v1::SceneUploadHeader upload_header(const SceneFiles& files, const std::string& name) {
  luxel::v1::SceneUploadHeader h;
  h.set_name(name.empty() ? fs::path(files.main.path).filename().string() : name);
  h.set_format(files.format);
  h.set_total_size(files.main.size);
  h.set_sha256(files.main.sha256);
  for (const SceneFile& r : files.resources) {
    auto* rh = h.add_resources();
    rh->set_uri(r.uri);
    rh->set_size(r.size);
    rh->set_sha256(r.sha256);
  }
  return h;
}

}  // namespace luxel::cli::remote
