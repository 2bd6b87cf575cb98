#include "service/scene_upload.h"

#include <fcntl.h>
#include <unistd.h>

#include <filesystem>
#include <set>

#include "common/uri.h"
#include "service/files.h"

namespace luxel::service {

namespace fs = std::filesystem;

Status check_resource_uri(const std::string& uri) {
  auto bad = [&](const char* why) {
    return invalid_argument(strprintf("header.resources.uri '%s': %s", uri.c_str(), why));
  };
  if (uri.empty()) return bad("empty");
  if (uri.size() > 1024) return bad("longer than 1024 characters");
  if (uri[0] == '/') return bad("absolute paths are not allowed");
  if (uri.find('\\') != std::string::npos) return bad("backslashes are not allowed");
  if (uri.find(':') != std::string::npos)
    return bad("schemes (data:, file:, ...) are not uploaded");
  if (uri.find('\0') != std::string::npos) return bad("NUL byte");
  size_t start = 0;
  while (start <= uri.size()) {
    const size_t end = std::min(uri.find('/', start), uri.size());
    const std::string part = uri.substr(start, end - start);
    if (part.empty() || part == "." || part == "..")
      return bad("empty, '.' and '..' path components would escape or alias the scene folder");
    start = end + 1;
  }
  if (uri == "scene.gltf" || uri == "scene.glb" || uri == "info.json")
    return bad("name reserved by the scene store");
  return Status::ok();
}

namespace {

// RFC 3629: no overlong forms, no surrogates, nothing past U+10FFFF.
bool is_valid_utf8(const std::string& s) {
  size_t i = 0;
  while (i < s.size()) {
    const auto c = static_cast<unsigned char>(s[i]);
    int n = 0;
    uint32_t cp = 0;
    if (c < 0x80) {
      ++i;
      continue;
    } else if ((c & 0xe0) == 0xc0) {
      n = 1, cp = c & 0x1f;
    } else if ((c & 0xf0) == 0xe0) {
      n = 2, cp = c & 0x0f;
    } else if ((c & 0xf8) == 0xf0) {
      n = 3, cp = c & 0x07;
    } else {
      return false;
    }
    if (i + static_cast<size_t>(n) >= s.size()) return false;  // truncated sequence
    for (int k = 1; k <= n; ++k) {
      const auto d = static_cast<unsigned char>(s[i + static_cast<size_t>(k)]);
      if ((d & 0xc0) != 0x80) return false;
      cp = (cp << 6) | (d & 0x3f);
    }
    const uint32_t min[4] = {0, 0x80, 0x800, 0x10000};
    if (cp < min[n] || cp > 0x10ffff || (cp >= 0xd800 && cp <= 0xdfff)) return false;
    i += static_cast<size_t>(n) + 1;
  }
  return true;
}

}  // namespace

Status check_scene_name(const std::string& name) {
  if (name.size() > kMaxSceneNameBytes)
    return invalid_argument(
        strprintf("header.name: %zu bytes; at most %zu", name.size(), kMaxSceneNameBytes));
  for (size_t i = 0; i < name.size(); ++i) {
    const auto c = static_cast<unsigned char>(name[i]);
    if (c < 0x20 || c == 0x7f)
      return invalid_argument(strprintf(
          "header.name: control character 0x%02x at byte %zu (names are one printable line)", c,
          i));
  }
  if (!is_valid_utf8(name)) return invalid_argument("header.name: not valid UTF-8");
  return Status::ok();
}

Result<std::unique_ptr<SceneUpload>> SceneUpload::begin(SceneStore& store,
                                                        const v1::SceneUploadHeader& header,
                                                        const UploadLimits& limits) {
  LUXEL_RETURN_IF_ERROR(check_scene_name(header.name()));
  if (header.format() != v1::SCENE_FORMAT_GLTF && header.format() != v1::SCENE_FORMAT_GLB)
    return invalid_argument("header.format: must be SCENE_FORMAT_GLTF or SCENE_FORMAT_GLB");
  if (!is_sha256_hex(header.sha256()))
    return invalid_argument(strprintf("header.sha256: expected 64 lowercase hex digits, got '%s'",
                                      header.sha256().substr(0, 80).c_str()));
  if (header.total_size() == 0) return invalid_argument("header.total_size: must be > 0");
  if (static_cast<size_t>(header.resources_size()) > limits.max_resources)
    return resource_exhausted(strprintf("header.resources: %d resources exceed the limit of %zu",
                                        header.resources_size(), limits.max_resources));
  uint64_t total = header.total_size();
  std::set<std::string> uris;
  std::vector<std::string> paths;  // decoded, relative to the scene folder
  for (const auto& r : header.resources()) {
    // glTF uris are URI references: "tex%20a.png" names the file "tex a.png"
    // (common/uri.h, as the importer reads it). Decoding first also means
    // "%2e%2e" cannot slip past the path checks below.
    auto decoded = percent_decode_uri(r.uri());
    if (!decoded) return invalid_argument("header.resources.uri: " + decoded.status().message());
    LUXEL_RETURN_IF_ERROR(check_resource_uri(decoded.value()));
    paths.push_back(decoded.value());
    if (!uris.insert(decoded.value()).second)
      return invalid_argument(
          strprintf("header.resources.uri '%s': listed twice", r.uri().c_str()));
    if (!is_sha256_hex(r.sha256()))
      return invalid_argument(strprintf(
          "header.resources.sha256 of '%s': expected 64 lowercase hex digits", r.uri().c_str()));
    if (r.size() > limits.max_upload_bytes)
      total = limits.max_upload_bytes + 1;
    else
      total += r.size();
  }
  // A path that is another's folder ("a" and "a/b") cannot be both a file
  // and a folder on disk.
  for (const std::string& p : paths) {
    const auto lo = uris.lower_bound(p + "/");
    if (lo != uris.end() && lo->compare(0, p.size() + 1, p + "/") == 0)
      return invalid_argument(strprintf(
          "header.resources.uri '%s': also the folder of '%s'; a path cannot be a file and a "
          "folder",
          p.c_str(), lo->c_str()));
  }
  if (total > limits.max_upload_bytes || header.total_size() > limits.max_upload_bytes)
    return resource_exhausted(
        strprintf("upload of %llu bytes exceeds the daemon's limit --max-upload-bytes=%llu",
                  static_cast<unsigned long long>(total),
                  static_cast<unsigned long long>(limits.max_upload_bytes)));

  auto staging = store.new_staging_dir();
  if (!staging) return staging.status();
  std::unique_ptr<SceneUpload> up(new SceneUpload(store, header, staging.value()));
  up->expected_ = total;
  up->files_.push_back({staging.value() + "/" + SceneStore::main_file_name(header.format()),
                        "main file '" + header.name() + "'", header.sha256(), header.total_size()});
  for (int i = 0; i < header.resources_size(); ++i) {
    const auto& r = header.resources(i);
    up->files_.push_back({staging.value() + "/" + paths[static_cast<size_t>(i)],
                          "resource '" + r.uri() + "'", r.sha256(), r.size()});
  }
  LUXEL_RETURN_IF_ERROR(up->open_next_file());
  return up;
}

SceneUpload::SceneUpload(SceneStore& store, v1::SceneUploadHeader header, std::string staging)
    : store_(store), header_(std::move(header)), staging_(std::move(staging)) {}

SceneUpload::~SceneUpload() {
  if (!committed_) remove_tree(staging_);
}

Status SceneUpload::open_next_file() {
  // Skip empty resources (a zero-byte file is legal): create them at once.
  while (current_ < files_.size()) {
    const FileSlot& f = files_[current_];
    LUXEL_RETURN_IF_ERROR(make_directories(fs::path(f.path).parent_path().string()));
    out_ = std::ofstream(f.path, std::ios::binary | std::ios::trunc);
    if (!out_) return internal_error(strprintf("%s: cannot create", f.path.c_str()));
    hash_ = std::make_unique<Sha256>();
    written_in_current_ = 0;
    if (f.size > 0) return Status::ok();
    LUXEL_RETURN_IF_ERROR(close_current_file());
  }
  return Status::ok();
}

Status SceneUpload::close_current_file() {
  const FileSlot& f = files_[current_];
  out_.flush();
  const bool ok = static_cast<bool>(out_);
  out_.close();
  if (!ok) return internal_error(strprintf("%s: write failed (disk full?)", f.path.c_str()));
  // Durable before the commit renames the folder into the store.
  const int fd = ::open(f.path.c_str(), O_RDONLY);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
  const std::string got = hash_->hex_digest();
  if (got != f.sha256)
    return data_loss(strprintf("%s: sha256 mismatch: header says %s, received bytes hash to %s",
                               f.what.c_str(), f.sha256.c_str(), got.c_str()));
  ++current_;
  return Status::ok();
}

Status SceneUpload::write(const std::string& chunk) {
  size_t pos = 0;
  while (pos < chunk.size()) {
    if (current_ >= files_.size())
      return data_loss(strprintf("upload: more bytes than the %llu the header declares",
                                 static_cast<unsigned long long>(expected_)));
    const FileSlot& f = files_[current_];
    const size_t n =
        static_cast<size_t>(std::min<uint64_t>(chunk.size() - pos, f.size - written_in_current_));
    out_.write(chunk.data() + pos, static_cast<std::streamsize>(n));
    hash_->update(chunk.data() + pos, n);
    pos += n;
    written_in_current_ += n;
    received_ += n;
    if (written_in_current_ == f.size) {
      LUXEL_RETURN_IF_ERROR(close_current_file());
      LUXEL_RETURN_IF_ERROR(open_next_file());
    }
  }
  return Status::ok();
}

Result<v1::SceneInfo> SceneUpload::finish() {
  if (current_ < files_.size())
    return data_loss(strprintf("upload truncated: received %llu of %llu bytes (stream ended in %s)",
                               static_cast<unsigned long long>(received_),
                               static_cast<unsigned long long>(expected_),
                               files_[current_].what.c_str()));
  committed_ = true;  // commit() owns (and always removes) the staging folder now
  return store_.commit(staging_, header_, received_);
}

}  // namespace luxel::service
