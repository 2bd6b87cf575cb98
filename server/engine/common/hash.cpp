#include "common/hash.h"

#include <cstdio>

namespace luxel {

Hasher& Hasher::add(const void* data, size_t size) {
  // Length-prefix each field so ("ab","c") and ("a","bc") differ.
  return add_length(size).add_piece(data, size);
}

Hasher& Hasher::add_length(uint64_t len) {
  for (int i = 0; i < 8; ++i) {
    const unsigned char c = static_cast<unsigned char>(len >> (8 * i));
    a_ = fnv1a_step(a_, c);
    b_ = fnv1a_step(b_, c + 0x5bu);
  }
  return *this;
}

Hasher& Hasher::add_piece(const void* data, size_t size) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < size; ++i) {
    a_ = fnv1a_step(a_, p[i]);
    b_ = fnv1a_step(b_, static_cast<unsigned char>(p[i] + 0x5bu));
  }
  return *this;
}

Hasher& Hasher::add(std::string_view bytes) {
  return add(bytes.data(), bytes.size());
}

std::string Hasher::hex() const {
  char buf[33];
  std::snprintf(buf, sizeof buf, "%016llx%016llx", static_cast<unsigned long long>(a_),
                static_cast<unsigned long long>(b_));
  return buf;
}

}  // namespace luxel
