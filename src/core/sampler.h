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

#include <array>

#if (defined(__GFNI__) && defined(__SSE2__)) || defined(__SSE4_1__)
#include <immintrin.h>
#endif

namespace kozu {

namespace sobol {

inline uint32_t reverse_bits(uint32_t x) {
#if defined(__GFNI__) && defined(__SSE2__)
  // One GF(2) affine transform reverses the bits of every byte; a byte swap finishes the job.
  __m128i v = _mm_cvtsi32_si128(static_cast<int>(x));
  v = _mm_gf2p8affine_epi64_epi8(v, _mm_set1_epi64x(0x8040201008040201LL), 0);
  return __builtin_bswap32(static_cast<uint32_t>(_mm_cvtsi128_si32(v)));
#else
  x = (x << 16) | (x >> 16);
  x = ((x & 0x00ff00ffU) << 8) | ((x & 0xff00ff00U) >> 8);
  x = ((x & 0x0f0f0f0fU) << 4) | ((x & 0xf0f0f0f0U) >> 4);
  x = ((x & 0x33333333U) << 2) | ((x & 0xccccccccU) >> 2);
  x = ((x & 0x55555555U) << 1) | ((x & 0xaaaaaaaaU) >> 1);
  return x;
#endif
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

#if defined(__SSE4_1__)
// reverse_bits and lk_permutation on four lanes at once (below): next_4d's four scrambles are independent, and as
// scalar chains of multiplies they were a third of a Cornell-box vertex's own time (perf annotate of
// Path::surface_vertex).

// The bytes of each 32-bit lane in reverse order.
inline __m128i swap_bytes4(__m128i x) {
  return _mm_shuffle_epi8(x, _mm_setr_epi8(3, 2, 1, 0, 7, 6, 5, 4, 11, 10, 9, 8, 15, 14, 13, 12));
}

// reverse_bits of each lane without GFNI (CPUs before it, e.g. AMD Zen 2 and 3): each byte's bits reversed through a
// nibble table (PSHUFB), rev(b) = rev4(low) << 4 | rev4(high), then the bytes swapped. Compiled wherever SSE4.1 is,
// so that the tests check it on GFNI machines too.
inline __m128i reverse_bits4_by_table(__m128i x) {
  const __m128i rev4 = _mm_setr_epi8(0x0, 0x8, 0x4, 0xc, 0x2, 0xa, 0x6, 0xe, 0x1, 0x9, 0x5, 0xd, 0x3, 0xb, 0x7, 0xf);
  const __m128i nibble = _mm_set1_epi8(0x0f);
  const __m128i lo = _mm_shuffle_epi8(rev4, _mm_and_si128(x, nibble));
  const __m128i hi = _mm_shuffle_epi8(rev4, _mm_and_si128(_mm_srli_epi16(x, 4), nibble));
  return swap_bytes4(_mm_or_si128(_mm_slli_epi16(lo, 4), hi));
}

inline __m128i reverse_bits4(__m128i x) {
#if defined(__GFNI__)
  // One GF(2) affine transform reverses the bits of every byte; the byte swap finishes the job.
  return swap_bytes4(_mm_gf2p8affine_epi64_epi8(x, _mm_set1_epi64x(0x8040201008040201LL), 0));
#else
  return reverse_bits4_by_table(x);
#endif
}

inline __m128i lk_permutation4(__m128i x, __m128i seed) {
  x = _mm_xor_si128(x, _mm_mullo_epi32(x, _mm_set1_epi32(0x3d20adea)));
  x = _mm_add_epi32(x, seed);
  x = _mm_mullo_epi32(x, _mm_or_si128(_mm_srli_epi32(seed, 16), _mm_set1_epi32(1)));
  x = _mm_xor_si128(x, _mm_mullo_epi32(x, _mm_set1_epi32(0x05526c56)));
  x = _mm_xor_si128(x, _mm_mullo_epi32(x, _mm_set1_epi32(0x53a22864)));
  return x;
}
#endif

inline uint32_t nested_uniform_scramble(uint32_t x, uint32_t seed) {
  return reverse_bits(lk_permutation(reverse_bits(x), seed));
}

// Direction numbers of Sobol dimensions 1-3 (dimension 0 is the van der Corput sequence), from
// the primitive polynomials and initial numbers of Joe & Kuo 2008 ("new-joe-kuo-6.21201": s = 1,
// a = 0, m = {1}; s = 2, a = 1, m = {1, 3}; s = 3, a = 1, m = {1, 3, 1}), with the recurrence
// V_i = V_{i-s} ^ (V_{i-s} >> s) ^ sum_k a_k V_{i-k}.
constexpr std::array<uint32_t, 32> sobol_directions(int s, uint32_t a, std::array<uint32_t, 3> m) {
  std::array<uint32_t, 33> v{};
  for (int i = 1; i <= s; ++i) v[i] = m[i - 1] << (32 - i);
  for (int i = s + 1; i <= 32; ++i) {
    v[i] = v[i - s] ^ (v[i - s] >> s);
    for (int k = 1; k <= s - 1; ++k)
      if ((a >> (s - 1 - k)) & 1u) v[i] ^= v[i - k];
  }
  std::array<uint32_t, 32> out{};
  for (int i = 0; i < 32; ++i) out[i] = v[i + 1];
  return out;
}

constexpr uint32_t reverse_bits_constexpr(uint32_t x) {
  uint32_t r = 0;
  for (int i = 0; i < 32; ++i) r |= ((x >> i) & 1u) << (31 - i);
  return r;
}

// Bit-reversed Sobol dimensions 1-3 of an index, a byte of the index at a time: Owen scrambling
// works on reversed values, so storing the reversed directions saves a reversal per output.
struct SobolTables {
  uint32_t t[3][4][256];
  constexpr SobolTables() : t{} {
    const std::array<std::array<uint32_t, 32>, 3> dirs = {
        sobol_directions(1, 0, {1, 0, 0}), sobol_directions(2, 1, {1, 3, 0}), sobol_directions(3, 1, {1, 3, 1})};
    for (int d = 0; d < 3; ++d)
      for (int byte = 0; byte < 4; ++byte)
        for (uint32_t b = 0; b < 256; ++b) {
          uint32_t r = 0;
          for (int j = 0; j < 8; ++j)
            if (b & (1u << j)) r ^= reverse_bits_constexpr(dirs[d][8 * byte + j]);
          t[d][byte][b] = r;
        }
  }
};
inline constexpr SobolTables kSobolTables{};

// reverse_bits(Sobol dimension d + 1 of index i), d in 0..2.
inline uint32_t sobol_reversed(int d, uint32_t i) {
  const auto& t = kSobolTables.t[d];
  return t[0][i & 255u] ^ t[1][(i >> 8) & 255u] ^ t[2][(i >> 16) & 255u] ^ t[3][i >> 24];
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

  // Four dimensions of one shuffled, scrambled 4D Sobol point (Burley 2020, listing 3). Pairs that
  // need the best 2D stratification go in components 0 and 1 (a (0, 2)-sequence).
  Vec4 next_4d() {
#if defined(__SSE4_1__)
    const auto [i, h01, h23] = next_point4();
    // Lanes x, y, z, w as next_4d_portable's, their seeds the low and high halves of h01 and h23.
    const __m128i v = _mm_setr_epi32(static_cast<int>(i), static_cast<int>(sobol::sobol_reversed(0, i)),
                                     static_cast<int>(sobol::sobol_reversed(1, i)),
                                     static_cast<int>(sobol::sobol_reversed(2, i)));
    const __m128i seeds = _mm_set_epi64x(static_cast<long long>(h23), static_cast<long long>(h01));
    const __m128i r = sobol::reverse_bits4(sobol::lk_permutation4(v, seeds));
    // u32_to_unit_float per lane: the top 24 bits, exact in a float.
    const __m128 f = _mm_mul_ps(_mm_cvtepi32_ps(_mm_srli_epi32(r, 8)), _mm_set1_ps(0x1p-24f));
    alignas(16) float out[4];
    _mm_store_ps(out, f);
    return Vec4(out[0], out[1], out[2], out[3]);
#else
    return next_4d_portable();
#endif
  }

  // next_4d in scalar code: the same numbers bit for bit (the reference its SIMD form is tested against).
  Vec4 next_4d_portable() {
    const auto [i, h01, h23] = next_point4();
    const uint32_t x = scramble_reversed(i, static_cast<uint32_t>(h01));
    const uint32_t y = scramble_reversed(sobol::sobol_reversed(0, i), static_cast<uint32_t>(h01 >> 32));
    const uint32_t z = scramble_reversed(sobol::sobol_reversed(1, i), static_cast<uint32_t>(h23));
    const uint32_t w = scramble_reversed(sobol::sobol_reversed(2, i), static_cast<uint32_t>(h23 >> 32));
    return Vec4(u32_to_unit_float(x), u32_to_unit_float(y), u32_to_unit_float(z), u32_to_unit_float(w));
  }

  Vec2 next_2d() {
    const uint32_t s = hash_combine(pixel_seed_, dimension_++);
    const uint32_t i = shuffled_index(s);
    const uint64_t h = mix64((static_cast<uint64_t>(s) << 32) | 0x4b6f7a75U);
    const uint32_t x = scramble_reversed(i, static_cast<uint32_t>(h));
    const uint32_t y = scramble_reversed(sobol::sobol_reversed(0, i), static_cast<uint32_t>(h >> 32));
    return Vec2(u32_to_unit_float(x), u32_to_unit_float(y));
  }

  float next_1d() {
    const uint32_t s = hash_combine(pixel_seed_, dimension_++);
    const uint32_t i = shuffled_index(s);
    return u32_to_unit_float(scramble_reversed(i, hash_u32(s ^ 0xa511e9b3U)));
  }

  uint32_t dimension() const { return dimension_; }

 private:
  // The next 4D slot's shuffled index and the hashes whose four halves seed its four scrambles (both forms of
  // next_4d).
  struct Point4 {
    uint32_t index;
    uint64_t h01, h23;
  };
  Point4 next_point4() {
    const uint32_t s = hash_combine(pixel_seed_, dimension_++);
    const uint64_t h01 = mix64((static_cast<uint64_t>(s) << 32) | 0x4b6f7a75U);
    return {shuffled_index(s), h01, mix64(h01 ^ 0x9e3779b97f4a7c15ull)};
  }
  // Owen-scrambled (shuffled) sample index for a dimension slot: the order differs per slot.
  uint32_t shuffled_index(uint32_t s) const { return sobol::reverse_bits(sobol::lk_permutation(index_reversed_, s)); }
  // Owen scrambling of a value given bit-reversed; returns the scrambled value in normal order.
  // (Sobol dimension 0 of index i is reverse_bits(i), so i itself is its reversed value.)
  static uint32_t scramble_reversed(uint32_t reversed, uint32_t seed) {
    return sobol::reverse_bits(sobol::lk_permutation(reversed, seed));
  }

  uint32_t seed_;
  uint32_t pixel_seed_ = 0;
  uint32_t index_reversed_ = 0;
  uint32_t dimension_ = 0;
};

}  // namespace kozu
