// Padded, Owen-scrambled Sobol sampler.
// Burley 2020, "Practical Hash-based Owen Scrambling" (JCGT 9(4)): every pair of dimensions is
// the 2D Sobol (0, 2)-sequence, Owen-scrambled and index-shuffled with its own hash seed, so the
// pairs are decorrelated from each other while each keeps its stratification. The Laine–Karras
// style permutation uses the constants of N. Vegdahl, "Building a Better LK Hash" (2021).
//
// Determinism: a sample's stream depends only on (seed, pixel, sample index, dimension), never
// on thread or tile, so images are bit-identical for any thread count.
#pragma once

#include "core/math.h"
#include "core/rng.h"

namespace kozu {

namespace sobol {

inline uint32_t reverse_bits(uint32_t x) {
  x = (x << 16) | (x >> 16);
  x = ((x & 0x00ff00ffU) << 8) | ((x & 0xff00ff00U) >> 8);
  x = ((x & 0x0f0f0f0fU) << 4) | ((x & 0xf0f0f0f0U) >> 4);
  x = ((x & 0x33333333U) << 2) | ((x & 0xccccccccU) >> 2);
  x = ((x & 0x55555555U) << 1) | ((x & 0xaaaaaaaaU) >> 1);
  return x;
}

// Owen scrambling acts on bit-reversed values as a hash whose every bit depends only on lower bits.
inline uint32_t lk_permutation(uint32_t x, uint32_t seed) {
  x ^= x * 0x3d20adeaU;
  x += seed;
  x *= (seed >> 16) | 1U;
  x ^= x * 0x05526c56U;
  x ^= x * 0x53a22864U;
  return x;
}

inline uint32_t nested_uniform_scramble(uint32_t x, uint32_t seed) {
  return reverse_bits(lk_permutation(reverse_bits(x), seed));
}

// Second Sobol dimension (primitive polynomial x + 1); the first is the van der Corput sequence.
// Direction numbers: v_0 = 2^31, v_k = v_{k-1} ^ (v_{k-1} >> 1). The Owen-shuffled index has all 32
// bits set at random, so the generator matrix is applied a byte at a time from tables.
struct SobolDim1Tables {
  uint32_t t[4][256];
  constexpr SobolDim1Tables() : t{} {
    uint32_t v[32] = {};
    v[0] = 1u << 31;
    for (int k = 1; k < 32; ++k) v[k] = v[k - 1] ^ (v[k - 1] >> 1);
    for (int byte = 0; byte < 4; ++byte)
      for (uint32_t b = 0; b < 256; ++b) {
        uint32_t r = 0;
        for (int j = 0; j < 8; ++j)
          if (b & (1u << j)) r ^= v[8 * byte + j];
        t[byte][b] = r;
      }
  }
};
inline constexpr SobolDim1Tables kSobolDim1{};

inline uint32_t sobol_dim1(uint32_t i) {
  return kSobolDim1.t[0][i & 255u] ^ kSobolDim1.t[1][(i >> 8) & 255u] ^ kSobolDim1.t[2][(i >> 16) & 255u] ^
         kSobolDim1.t[3][i >> 24];
}

}  // namespace sobol

class Sampler {
 public:
  explicit Sampler(uint32_t seed = 0) : seed_(hash_u32(seed ^ 0x6b79757aU)) {}

  // Positions the stream at (pixel, sample index), dimension 0.
  void start(uint32_t px, uint32_t py, uint32_t sample_index) {
    pixel_seed_ = hash_combine(hash_combine(seed_, px), py);
    index_reversed_ = sobol::reverse_bits(sample_index);
    dimension_ = 0;
  }

  float next_1d() {
    const uint32_t s = hash_combine(pixel_seed_, dimension_++);
    const uint32_t i = shuffled_index(s);
    // Sobol dimension 0 of i is reverse_bits(i), so its Owen scrambling needs one reversal only.
    return u32_to_unit_float(sobol::reverse_bits(sobol::lk_permutation(i, hash_u32(s ^ 0xa511e9b3U))));
  }

  Vec2 next_2d() {
    const uint32_t s = hash_combine(pixel_seed_, dimension_++);
    const uint32_t i = shuffled_index(s);
    const uint32_t x = sobol::reverse_bits(sobol::lk_permutation(i, hash_u32(s ^ 0xa511e9b3U)));
    const uint32_t y = sobol::nested_uniform_scramble(sobol::sobol_dim1(i), hash_u32(s ^ 0x63d83595U));
    return Vec2(u32_to_unit_float(x), u32_to_unit_float(y));
  }

  uint32_t dimension() const { return dimension_; }

 private:
  uint32_t seed_;
  uint32_t pixel_seed_ = 0;
  // Owen-scrambled (shuffled) sample index for a dimension: the sample order differs per dimension.
  uint32_t shuffled_index(uint32_t s) const { return sobol::reverse_bits(sobol::lk_permutation(index_reversed_, s)); }

  uint32_t index_reversed_ = 0;
  uint32_t dimension_ = 0;
};

}  // namespace kozu
