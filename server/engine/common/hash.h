// Stable 128-bit content hash (two independent 64-bit FNV-1a lanes).
// Used for cache keys, where stability across runs and builds matters and
// cryptographic strength does not (scene content addressing uses SHA-256).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace luxel {

// 64-bit FNV-1a (Fowler, Noll, Vo): the standard offset basis, the prime and
// one step. Hasher runs it a byte at a time; an in-memory hash table may run
// it a word at a time, where speed matters more than mixing.
inline constexpr uint64_t kFnv1aBasis = 0xcbf29ce484222325ull;
inline constexpr uint64_t kFnv1aPrime = 0x100000001b3ull;
constexpr uint64_t fnv1a_step(uint64_t h, uint64_t v) {
  return (h ^ v) * kFnv1aPrime;
}

// FNV-1a of `bytes` in one lane without Hasher's length prefix, from
// `basis`: for short fingerprint fields whose text must not change.
constexpr uint64_t fnv1a64(std::string_view bytes, uint64_t basis = kFnv1aBasis) {
  uint64_t h = basis;
  for (char c : bytes) h = fnv1a_step(h, static_cast<unsigned char>(c));
  return h;
}

class Hasher {
 public:
  Hasher& add(std::string_view bytes);
  Hasher& add(const void* data, size_t size);
  Hasher& add_u64(uint64_t v) { return add(&v, sizeof v); }
  // One field given in pieces: add(data, size) is add_length(size) then
  // add_piece for its bytes in order, however they are split (a file
  // hashed as it is streamed out).
  Hasher& add_length(uint64_t size);
  Hasher& add_piece(const void* data, size_t size);
  // 32 lowercase hex digits.
  std::string hex() const;

 private:
  uint64_t a_ = kFnv1aBasis;
  uint64_t b_ = 0x84222325cbf29ce4ull;
};

}  // namespace luxel
