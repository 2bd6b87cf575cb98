// PCG32 (O'Neill 2014, pcg32_random_r: XSH RR output, 64-bit LCG state):
// the reference tracer's random numbers, one stream per texel.
#pragma once

#include <cstdint>

namespace luxel::reference {

class Pcg32 {
 public:
  // `stream` selects one of 2^63 independent sequences (any value).
  Pcg32(uint64_t seed, uint64_t stream) : inc_((stream << 1u) | 1u) {
    next();
    state_ += seed;
    next();
  }

  uint32_t next() {
    const uint64_t old = state_;
    state_ = old * 6364136223846793005ULL + inc_;
    const uint32_t xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
    const uint32_t rot = static_cast<uint32_t>(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
  }

  // Uniform in [0, 1) with 53 random bits.
  double uniform() {
    const uint64_t hi = next() >> 5, lo = next() >> 6;  // 27 + 26 bits
    return static_cast<double>((hi << 26) | lo) * 0x1p-53;
  }

  // Uniform integer in [0, n), n > 0, without modulo bias (rejection).
  uint32_t bounded(uint32_t n) {
    const uint32_t threshold = (0u - n) % n;  // 2^32 mod n
    for (;;) {
      const uint32_t r = next();
      if (r >= threshold) return r % n;
    }
  }

 private:
  uint64_t state_ = 0;
  uint64_t inc_;
};

}  // namespace luxel::reference
