// Stable 128-bit content hash (two independent 64-bit FNV-1a lanes).
// Used for cache keys, where stability across runs and builds matters and
// cryptographic strength does not (scene content addressing uses SHA-256).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace luxel {

class Hasher {
 public:
  Hasher& add(std::string_view bytes);
  Hasher& add(const void* data, size_t size);
  Hasher& add_u64(uint64_t v) { return add(&v, sizeof v); }
  // 32 lowercase hex digits.
  std::string hex() const;

 private:
  uint64_t a_ = 0xcbf29ce484222325ull;
  uint64_t b_ = 0x84222325cbf29ce4ull;
};

}  // namespace luxel
