// Discrete and piecewise-constant distributions: used for light selection by power and for
// importance sampling of environment maps.
#pragma once

#include "core/math.h"

#include <cstdint>
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

// One row of a piecewise-constant density on [0, 1) with n equal cells, in memory its Distribution owns: n + 1
// (cdf, weight) pairs, the cdf at each cell's start beside that cell's weight (the last pair: 1, 0), so a sample reads
// the weight from the cache line its search ended on, and a guide table (Chen and Asau 1974): guide[k] = the index
// std::upper_bound returns for u = k / n. A sample's search runs between the entries about floor(u n), a step or two
// instead of log2(n) cache-missing ones, and returns the same cell as the search over the whole cdf.
struct CdfCell {
  float cdf;
  float func;
};

namespace distribution_row {
// Fills cells (n + 1) and guide (n + 1) from func (n weights, negative and non-finite ones as 0); returns the
// integral, sum / n.
float build(std::span<const float> func, CdfCell* cells, uint32_t* guide);
// Continuous sample x in [0, 1) of the row; fills pdf (per unit length) and the cell index.
float sample(const CdfCell* cells, const uint32_t* guide, size_t n, float integral, float u, float* pdf,
             uint32_t* cell);
// The cdf at x.
float invert(const CdfCell* cells, size_t n, float x);
}  // namespace distribution_row

// Piecewise-constant density on [0, 1) with n equal cells.
class Distribution1D {
 public:
  Distribution1D() = default;
  explicit Distribution1D(std::span<const float> func);

  size_t size() const { return cells_.empty() ? 0 : cells_.size() - 1; }
  float integral() const { return integral_; }
  // Continuous sample x in [0, 1); returns x, fills pdf (per unit length) and the cell index.
  float sample(float u, float* pdf, uint32_t* cell = nullptr) const {
    return distribution_row::sample(cells_.data(), guide_.data(), size(), integral_, u, pdf, cell);
  }
  float pdf(float x) const;
  float invert(float x) const { return distribution_row::invert(cells_.data(), size(), x); }
  float cell_value(uint32_t i) const { return cells_[i].func; }

 private:
  std::vector<CdfCell> cells_;  // n + 1
  std::vector<uint32_t> guide_;  // n + 1
  float integral_ = 0;
};

// Piecewise-constant density on [0, 1)^2 sampled by marginal in v, conditional in u. The rows lie end to end in one
// buffer (and their guides in another), so a sample's conditional costs no lookup of a row object of its own: on
// environment-lit renders these searches were cache misses on three arrays a row.
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
  // Where row v's cells and guide begin in cells_ and guide_.
  size_t row_offset(int v) const { return static_cast<size_t>(v) * (static_cast<size_t>(nu_) + 1); }

  int nu_ = 0, nv_ = 0;
  std::vector<CdfCell> cells_;   // nv rows of nu + 1
  std::vector<uint32_t> guide_;  // nv rows of nu + 1
  std::vector<float> row_integral_;
  Distribution1D marginal_;
};

}  // namespace kozu
