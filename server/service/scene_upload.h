// One UploadScene stream: checks the header against the limits, writes the
// bytes that follow into a staging folder (main file, then each resource
// under its relative uri), hashing as it goes, and verifies every file's size
// and sha256 at the end. The staging folder is removed unless the upload is
// handed to SceneStore::commit, so a failed, truncated or cancelled upload
// leaves nothing behind.
#pragma once

#include <cstdint>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "common/sha256.h"
#include "common/status.h"
#include "luxel/v1/luxel.pb.h"
#include "service/scene_store.h"

namespace luxel::service {

struct UploadLimits {
  uint64_t max_upload_bytes = uint64_t{1} << 30;  // main file + resources
  size_t max_resources = 4096;
};

// INVALID_ARGUMENT naming the field unless `uri` is a plain relative path
// inside the scene folder (no '..', no absolute path, no scheme, no '\').
Status check_resource_uri(const std::string& uri);

// Scene display names: at most kMaxSceneNameBytes of valid UTF-8 without
// control characters (a name is shown in lists and logs as one line);
// INVALID_ARGUMENT naming header.name otherwise.
constexpr size_t kMaxSceneNameBytes = 256;
Status check_scene_name(const std::string& name);

class SceneUpload {
 public:
  // Validates the header (INVALID_ARGUMENT naming the field; RESOURCE_EXHAUSTED
  // naming --max-upload-bytes) and creates the staging folder.
  static Result<std::unique_ptr<SceneUpload>> begin(SceneStore& store,
                                                    const v1::SceneUploadHeader& header,
                                                    const UploadLimits& limits);
  ~SceneUpload();

  // Appends bytes; DATA_LOSS when they run past the declared sizes or a file's
  // hash does not match once it is complete.
  Status write(const std::string& chunk);
  // DATA_LOSS unless every declared byte arrived; then commits to the store.
  Result<v1::SceneInfo> finish();

  uint64_t received() const { return received_; }
  const v1::SceneUploadHeader& header() const { return header_; }

 private:
  struct FileSlot {
    std::string path, what, sha256;
    uint64_t size = 0;
  };
  SceneUpload(SceneStore& store, v1::SceneUploadHeader header, std::string staging);
  Status open_next_file();
  Status close_current_file();

  SceneStore& store_;
  v1::SceneUploadHeader header_;
  std::string staging_;
  std::vector<FileSlot> files_;
  size_t current_ = 0;  // index of the file being written
  uint64_t written_in_current_ = 0;
  uint64_t received_ = 0, expected_ = 0;
  std::ofstream out_;
  std::unique_ptr<Sha256> hash_;
  bool committed_ = false;
};

}  // namespace luxel::service
