// File hashing for the CLI: how it names scenes (content addressing) and
// verifies what it uploads and downloads.
#pragma once

#include <grpcpp/support/status.h>

#include <cstddef>
#include <cstdint>
#include <string>

#include "common/sha256.h"

namespace luxel::cli::remote {

// Size and sha256 (common/sha256.h) of a file. NOT_FOUND / INTERNAL naming the path.
grpc::Status hash_file(const std::string& path, uint64_t& size, std::string& sha256_hex);

}  // namespace luxel::cli::remote
