// Downloading the artifacts of a finished bake (DownloadResult server
// stream), each verified against the size and sha256 the daemon sends and
// written atomically into the output folder.
#pragma once

#include <string>
#include <vector>

#include "remote/connection.h"

namespace luxel::cli::remote {

struct FetchedArtifact {
  std::string name;    // as the daemon lists it ("irradiance.exr")
  std::string path;    // where it was written
  uint64_t size = 0;   // bytes
  std::string sha256;  // verified hex digest
};

// Downloads one artifact into `out_dir`/name. DATA_LOSS (nothing written)
// when the bytes do not match the daemon's size or sha256.
grpc::Status download_artifact(Connection& conn, const std::string& bake_id,
                               const std::string& name, const std::string& out_dir,
                               FetchedArtifact& out);

// Downloads `names` (all of info.artifacts when empty), printing one line
// (or one JSON object) per artifact.
grpc::Status download_artifacts(Connection& conn, const luxel::v1::BakeInfo& info,
                                const std::vector<std::string>& names, const std::string& out_dir,
                                bool json);

}  // namespace luxel::cli::remote
