// Hashing and the PCG32 generator.
// PCG32: O'Neill 2014, "PCG: A Family of Simple Fast Space-Efficient Statistically Good
// Algorithms for Random Number Generation" (XSH-RR output, 64-bit LCG state).
#pragma once

#include <cstdint>

namespace kozu {

// 64-bit finaliser (splitmix64 / Stafford's "Mix13"): full avalanche, used to derive seeds.
inline uint64_t mix64(uint64_t x) {
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ull;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebull;
  x ^= x >> 31;
  return x;
}

// 32-bit integer hash (Wellons' "lowbias32"), cheap enough for per-dimension seeds.
inline uint32_t hash_u32(uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}

inline uint32_t hash_combine(uint32_t seed, uint32_t v) {
  return hash_u32(seed ^ (v + 0x9e3779b9U + (seed << 6) + (seed >> 2)));
}

inline float u32_to_unit_float(uint32_t x) { return static_cast<float>(x >> 8) * 0x1p-24f; }

class Pcg32 {
 public:
  Pcg32() { seed(0x853c49e6748fea9bull, 0xda3e39cb94b95bdbull); }
  explicit Pcg32(uint64_t init_state, uint64_t stream = 1) { seed(init_state, stream); }

  void seed(uint64_t init_state, uint64_t stream = 1) {
    state_ = 0;
    inc_ = (stream << 1u) | 1u;
    next_u32();
    state_ += init_state;
    next_u32();
  }

  uint32_t next_u32() {
    const uint64_t old = state_;
    state_ = old * 6364136223846793005ull + inc_;
    const uint32_t xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
    const uint32_t rot = static_cast<uint32_t>(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31));
  }

  float next_float() { return u32_to_unit_float(next_u32()); }
  double next_double() {
    const uint64_t hi = next_u32(), lo = next_u32();
    return static_cast<double>(((hi << 32) | lo) >> 11) * 0x1p-53;
  }

 private:
  uint64_t state_ = 0, inc_ = 0;
};

}  // namespace kozu
