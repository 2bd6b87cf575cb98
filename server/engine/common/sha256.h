// Incremental SHA-256 (OpenSSL EVP) for content addressing and download
// checksums, shared by the daemon and the CLI. Hex digests are lowercase,
// 64 characters.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>

namespace luxel {

class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;

  void update(const void* data, size_t size);
  void update(std::string_view bytes) { update(bytes.data(), bytes.size()); }
  // The digest of everything added; the object must not be updated after.
  std::string hex_digest();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

std::string sha256_hex(std::string_view bytes);

// True for 64 lowercase hex digits (what every id and digest here looks like).
bool is_sha256_hex(const std::string& s);

}  // namespace luxel
