// SHA-256 of files and streams (OpenSSL EVP), as lowercase hex: how the CLI
// names scenes (content addressing) and verifies what it uploads and downloads.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include <grpcpp/support/status.h>

namespace luxel::cli::remote {

class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;

  void update(const void* data, size_t bytes);
  // Lowercase hex of the digest; the hasher may not be updated afterwards.
  std::string hex_digest();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Size and sha256 of a file. NOT_FOUND / INTERNAL naming the path.
grpc::Status hash_file(const std::string& path, uint64_t& size, std::string& sha256_hex);

}  // namespace luxel::cli::remote
