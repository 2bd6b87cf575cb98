#include "api/file_hash.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <vector>

namespace luxel::cli::remote {

grpc::Status hash_file(const std::string& path, uint64_t& size, std::string& sha256_hex) {
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) {
    const int err = errno;
    return {err == ENOENT ? grpc::StatusCode::NOT_FOUND : grpc::StatusCode::INTERNAL,
            "cannot open '" + path + "': " + std::strerror(err)};
  }
  Sha256 hasher;
  std::vector<char> buf(1 << 20);
  size = 0;
  size_t n = 0;
  while ((n = std::fread(buf.data(), 1, buf.size(), f)) > 0) {
    hasher.update(buf.data(), n);
    size += n;
  }
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (failed) return {grpc::StatusCode::INTERNAL, "cannot read '" + path + "'"};
  sha256_hex = hasher.hex_digest();
  return grpc::Status::OK;
}

}  // namespace luxel::cli::remote
