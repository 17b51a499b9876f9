// Discrete and piecewise-constant distributions: used for light selection by power and for
// importance sampling of environment maps.
#pragma once

#include "core/math.h"

#include <span>
#include <vector>

namespace kozu {

// Walker's alias method (Vose's construction): O(1) sampling of an index with probability
// proportional to its weight, O(1) lookup of that probability.
class AliasTable {
 public:
  AliasTable() = default;
  explicit AliasTable(std::span<const float> weights);

  size_t size() const { return bins_.size(); }
  bool empty() const { return bins_.empty(); }
  // Returns an index; u in [0, 1). If u_remapped is given it receives a fresh uniform variate in
  // [0, 1) recovered from u's unused bits, so one random number can serve the next decision too.
  uint32_t sample(float u, float* u_remapped = nullptr) const;
  float pmf(uint32_t index) const { return bins_[index].p; }

 private:
  struct Bin {
    float q = 0;         // probability of keeping this bin
    float p = 0;         // normalised probability of this index
    uint32_t alias = 0;  // index taken otherwise
  };
  std::vector<Bin> bins_;
};

// Piecewise-constant density on [0, 1) with n equal cells.
class Distribution1D {
 public:
  Distribution1D() = default;
  explicit Distribution1D(std::span<const float> func);

  size_t size() const { return func_.size(); }
  float integral() const { return integral_; }
  // Continuous sample x in [0, 1); returns x, fills pdf (per unit length) and the cell index.
  float sample(float u, float* pdf, uint32_t* cell = nullptr) const;
  float pdf(float x) const;
  float invert(float x) const;
  float cell_value(uint32_t i) const { return func_[i]; }

 private:
  std::vector<float> func_;
  std::vector<float> cdf_;  // n + 1 entries, cdf_[n] = 1
  // Guide table (Chen and Asau 1974): guide_[k] = the index std::upper_bound returns for u = k / n. A sample's search
  // runs between the entries about floor(u n), a step or two instead of log2(n) cache-missing ones, and returns the
  // same cell as the search over the whole cdf.
  std::vector<uint32_t> guide_;
  float integral_ = 0;
};

// Piecewise-constant density on [0, 1)^2 sampled by marginal in v, conditional in u.
class Distribution2D {
 public:
  Distribution2D() = default;
  // func has nv rows of nu values, row-major.
  Distribution2D(std::span<const float> func, int nu, int nv);

  Vec2 sample(const Vec2& u, float* pdf) const;
  float pdf(const Vec2& p) const;
  Vec2 invert(const Vec2& p) const;
  float integral() const { return marginal_.integral(); }

 private:
  int nu_ = 0, nv_ = 0;
  std::vector<Distribution1D> conditional_;
  Distribution1D marginal_;
};

}  // namespace kozu
