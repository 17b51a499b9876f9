// Delta (spectral) tracking and ratio tracking (media/tracking.h) in a heterogeneous medium with a closed-form
// transmittance: σt(p, c) = k_c (a + b x) along the x axis, majorants tight per segment of a coarse grid
// (8 cells, each bounding its own interval), a different scale per channel, and albedo 1 or 0.6.
//  - ratio tracking's mean is T_c = exp(−k_c ∫ (a + b x) dx) for every channel;
//  - free-flight sampling's throughput on paths that pass has mean T_c, and on paths that scatter before x
//    has mean albedo-weighted ∫ σs T: for albedo 1, 1 − T_c(x) (the scattered-before-x fraction).
#include "media/tracking.h"

#include "core/rng.h"
#include "core/transform.h"
#include "geometry/ray_cone.h"
#include "media/grid_medium.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace kozu {
namespace {

class RampMedium final : public Medium {
 public:
  RampMedium(float a, float b, const Rgb& k, float albedo, float min_collisions = 0.0f)
      : a_(a), b_(b), k_(k), albedo_(albedo), min_collisions_(min_collisions) {}
  float ratio_tracking_min_collisions() const override { return min_collisions_; }
  MediumProperties properties(const Vec3& p, const Vec3&) const override {
    const Rgb st = k_ * std::max(0.0f, a_ + b_ * p.x);
    return {st, st * albedo_};
  }
  const PhaseFunction* phase(const Vec3&, Arena&) const override { return nullptr; }
  void majorants(const Vec3& o, const Vec3& d, float t0, float t1, MajorantVisitor& v) const override {
    // Eight equal segments of [t0, t1], each with the max of the ramp over it (the ray runs along +x).
    const float kmax = max_component(k_);
    for (int i = 0; i < 8; ++i) {
      const float ta = t0 + (t1 - t0) * i / 8, tb = t0 + (t1 - t0) * (i + 1) / 8;
      const float xa = o.x + ta * d.x, xb = o.x + tb * d.x;
      if (!v.segment(ta, tb, kmax * std::max(a_ + b_ * xa, a_ + b_ * xb))) return;
    }
  }
  // ∫_0^x σt(c) along the +x ray from the origin.
  double optical_depth(int c, double x) const { return k_[c] * (a_ * x + 0.5 * b_ * x * x); }

 private:
  float a_, b_;
  Rgb k_;
  float albedo_;
  float min_collisions_;
};

constexpr int kN = 400000;

TEST(Tracking, RatioTrackingMatchesClosedForm) {
  const RampMedium m(0.2f, 1.5f, Rgb(0.5f, 1.0f, 2.0f), 0.6f);
  const Ray ray{Vec3(0.0f), Vec3(1, 0, 0), kInfinity};
  for (float len : {0.3f, 1.0f, 2.0f}) {
    Pcg32 rng(11);
    double sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0};
    for (int i = 0; i < kN; ++i) {
      PathBudget budget;
      const Rgb T = ratio_tracking(m, ray, len, rng, budget);
      for (int c = 0; c < 3; ++c) {
        sum[c] += T[c];
        sum2[c] += double(T[c]) * T[c];
      }
    }
    for (int c = 0; c < 3; ++c) {
      const double mean = sum[c] / kN, se = std::sqrt(std::max(0.0, sum2[c] / kN - mean * mean) / kN);
      EXPECT_NEAR(mean, std::exp(-m.optical_depth(c, len)), 4 * se + 1e-5) << "length " << len << " channel " << c;
    }
  }
}

// Ratio tracking with its majorants raised to at least 4 tentative collisions a segment
// (Medium::ratio_tracking_min_collisions; the ramp's eight segments over 2 units expect 0.1–1.6 of their own): the
// same mean, the closed form, and a lower variance per channel than with the ramp's own majorants, from the same
// random numbers. A raised majorant used for the steps but not for the weights (or the reverse) moves the mean by
// far more than 4 standard errors.
TEST(Tracking, RaisedMajorantsKeepRatioTrackingUnbiasedAndLowerItsVariance) {
  const RampMedium own(0.2f, 1.5f, Rgb(0.5f, 1.0f, 2.0f), 0.6f);
  const RampMedium raised(0.2f, 1.5f, Rgb(0.5f, 1.0f, 2.0f), 0.6f, 4.0f);
  const Ray ray{Vec3(0.0f), Vec3(1, 0, 0), kInfinity};
  const float len = 2.0f;
  double var[2][3];
  int which = 0;
  for (const RampMedium* m : {&own, &raised}) {
    Pcg32 rng(12);
    double sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0};
    for (int i = 0; i < kN; ++i) {
      PathBudget budget;
      const Rgb T = ratio_tracking(*m, ray, len, rng, budget);
      for (int c = 0; c < 3; ++c) {
        sum[c] += T[c];
        sum2[c] += double(T[c]) * T[c];
      }
    }
    for (int c = 0; c < 3; ++c) {
      const double mean = sum[c] / kN;
      var[which][c] = std::max(0.0, sum2[c] / kN - mean * mean);
      EXPECT_NEAR(mean, std::exp(-m->optical_depth(c, len)), 4 * std::sqrt(var[which][c] / kN) + 1e-5)
          << (which ? "raised" : "own") << " channel " << c;
    }
    ++which;
  }
  for (int c = 0; c < 3; ++c) EXPECT_LT(var[1][c], 0.5 * var[0][c]) << "channel " << c;
}

TEST(Tracking, FreeFlightPassesWithTransmittanceAndScattersTheRest) {
  for (float albedo : {1.0f, 0.6f}) {
    const RampMedium m(0.2f, 1.5f, Rgb(0.5f, 1.0f, 2.0f), albedo);
    const Ray ray{Vec3(0.0f), Vec3(1, 0, 0), kInfinity};
    const float len = 1.2f;
    Pcg32 rng(12);
    double pass[3] = {0, 0, 0}, pass2[3] = {0, 0, 0}, scat[3] = {0, 0, 0}, scat2[3] = {0, 0, 0};
    for (int i = 0; i < kN; ++i) {
      Rgb beta(1.0f);
      float t;
      PathBudget budget;
      const bool scattered = sample_free_flight(m, ray, len, rng, beta, &t, budget);
      for (int c = 0; c < 3; ++c) {
        (scattered ? scat : pass)[c] += beta[c];
        (scattered ? scat2 : pass2)[c] += double(beta[c]) * beta[c];
      }
      if (scattered) {
        ASSERT_GE(t, 0.0f);
        ASSERT_LT(t, len);
      }
    }
    for (int c = 0; c < 3; ++c) {
      const double T = std::exp(-m.optical_depth(c, len));
      const double mp = pass[c] / kN, sp = std::sqrt(std::max(0.0, pass2[c] / kN - mp * mp) / kN);
      const double ms = scat[c] / kN, ss = std::sqrt(std::max(0.0, scat2[c] / kN - ms * ms) / kN);
      EXPECT_NEAR(mp, T, 4 * sp + 1e-5) << "albedo " << albedo << " channel " << c;
      // The expected weight at the scattering event is ∫ σs T dt = albedo (1 − T) for a constant albedo.
      EXPECT_NEAR(ms, albedo * (1.0 - T), 4 * ss + 1e-5) << "albedo " << albedo << " channel " << c;
    }
  }
}

// Levels of detail per lookup (Medium::level_for): a medium that is one ramp where the ray's cone is narrower than 1
// and a steeper one where it is wider. Tracking must walk each part of the ray in the level its cone's width picks,
// against that level's majorants: the transmittance is exp(−(optical depth of A over A's parts + of B over B's)).
class TwoLevelMedium final : public Medium {
 public:
  TwoLevelMedium() : fine_(0.2f, 1.5f, Rgb(0.5f, 1.0f, 2.0f), 1.0f), coarse_(1.0f, -0.3f, Rgb(0.8f, 0.4f, 1.5f), 1.0f) {}
  MediumProperties properties(const Vec3& p, const Vec3& d) const override { return fine_.properties(p, d); }
  const PhaseFunction* phase(const Vec3&, Arena&) const override { return nullptr; }
  void majorants(const Vec3& o, const Vec3& d, float t0, float t1, MajorantVisitor& v) const override {
    fine_.majorants(o, d, t0, t1, v);
  }
  Lod level_for(float width) const override {
    return width < 1.0f ? Lod{&fine_, 0.0f, 1.0f} : Lod{&coarse_, 1.0f, kInfinity};
  }
  // The optical depth over [0, length] along +x from the origin for the cone: its parts between the points where
  // the width crosses the levels' boundary (±1, in double), each in the level that serves its middle.
  double optical_depth(int c, float length, const RayCone& cone) const {
    std::vector<double> ends = {0.0, double(length)};
    for (const double w : {1.0, -1.0}) {
      const double t = cone.spread != 0.0f ? (w - cone.width) / double(cone.spread) : -1.0;
      if (t > 0.0 && t < length) ends.push_back(t);
    }
    std::sort(ends.begin(), ends.end());
    double depth = 0;
    for (size_t i = 0; i + 1 < ends.size(); ++i) {
      const double mid = 0.5 * (ends[i] + ends[i + 1]);
      const RampMedium& m = std::abs(cone.width + cone.spread * mid) < 1.0 ? fine_ : coarse_;
      depth += m.optical_depth(c, ends[i + 1]) - m.optical_depth(c, ends[i]);
    }
    return depth;
  }

 private:
  RampMedium fine_, coarse_;
};

TEST(Tracking, LevelsOfDetailFollowTheRayCone) {
  const TwoLevelMedium m;
  const Ray ray{Vec3(0.0f), Vec3(1, 0, 0), kInfinity};
  const float length = 2.0f;
  // Widening: fine over [0, 1], coarse over [1, 2]. Converging through a focus: coarse over [0, 1/3], fine over
  // (1/3, 5/3), coarse again. Constant and narrow: fine throughout.
  for (const RayCone cone : {RayCone{0.2f, 0.8f}, RayCone{1.5f, -1.5f}, RayCone{0.5f, 0.0f}}) {
    Pcg32 rng(21);
    double rt[3] = {}, rt2[3] = {}, ff[3] = {}, ff2[3] = {};
    for (int i = 0; i < kN; ++i) {
      PathBudget budget;
      const Rgb T = ratio_tracking(m, ray, length, rng, budget, cone);
      Rgb beta(1.0f);
      float t;
      const bool scattered = sample_free_flight(m, ray, length, rng, beta, &t, budget, cone);
      for (int c = 0; c < 3; ++c) {
        rt[c] += T[c];
        rt2[c] += double(T[c]) * T[c];
        const double pass = scattered ? 0.0 : beta[c];
        ff[c] += pass;
        ff2[c] += pass * pass;
      }
    }
    for (int c = 0; c < 3; ++c) {
      const double expect = std::exp(-m.optical_depth(c, length, cone));
      const double mr = rt[c] / kN, sr = std::sqrt(std::max(0.0, rt2[c] / kN - mr * mr) / kN);
      const double mf = ff[c] / kN, sf = std::sqrt(std::max(0.0, ff2[c] / kN - mf * mf) / kN);
      EXPECT_NEAR(mr, expect, 4 * sr + 1e-5) << "cone " << cone.width << " " << cone.spread << " channel " << c;
      EXPECT_NEAR(mf, expect, 4 * sf + 1e-5) << "cone " << cone.width << " " << cone.spread << " channel " << c;
    }
  }
  // The levels differ enough that walking the wrong one fails: fine only against the widening cone's mix.
  EXPECT_GT(std::abs(m.optical_depth(1, length, RayCone{0.2f, 0.8f}) - m.optical_depth(1, length, RayCone{})), 0.3);
}

// A GridMedium (voxel grid + majorant grid) holding a linear density ramp, which trilinear interpolation
// reproduces exactly between the outermost voxel centres: ratio tracking and free flights along local x match
// exp(−scale ∫ ρ) with ρ(x) = 0.5 + 6 x, at the majorant grid's own tightness. With a transform the ray is the
// scene image of the same local segment; density stays per scene unit, so the optical depth grows by the
// segment's stretch |M x̂|.
void expect_ramp_transmittance(const Transform& world_from_local, uint64_t seed) {
  const int n = 32;
  VoxelGrid grid(Vec3i(n, 8, 8), Vec3(0.0f), Vec3(1.0f), false);
  for (int k = 0; k < 8; ++k)
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < n; ++i) grid.set_voxel(i, j, k, 0.5f + 6.0f * (i + 0.5f) / n);
  const float scale = 0.7f;
  const GridMedium m(std::move(grid), scale, Rgb(1.0f), 0.0f, MediumTransform(world_from_local));
  const float x0 = 0.5f / n, x1 = 1.0f - 0.5f / n;
  const Vec3 axis = world_from_local.vector(Vec3(1, 0, 0));
  const float stretch = glm::length(axis);
  const Ray ray{world_from_local.point(Vec3(x0, 0.4f, 0.6f)), axis / stretch, kInfinity};
  const float length = stretch * (x1 - x0);
  const double expect = std::exp(-scale * stretch * (0.5 * (x1 - x0) + 3.0 * (x1 * x1 - x0 * x0)));
  Pcg32 rng(seed);
  double rt = 0, rt2 = 0, ff = 0, ff2 = 0;
  for (int i = 0; i < kN; ++i) {
    PathBudget budget;
    const double T = ratio_tracking(m, ray, length, rng, budget).g;
    rt += T;
    rt2 += T * T;
    Rgb beta(1.0f);
    float t;
    const double pass = sample_free_flight(m, ray, length, rng, beta, &t, budget) ? 0.0 : beta.g;
    ff += pass;
    ff2 += pass * pass;
  }
  const double mr = rt / kN, sr = std::sqrt(std::max(0.0, rt2 / kN - mr * mr) / kN);
  const double mf = ff / kN, sf = std::sqrt(std::max(0.0, ff2 / kN - mf * mf) / kN);
  EXPECT_NEAR(mr, expect, 4 * sr + 1e-5);
  EXPECT_NEAR(mf, expect, 4 * sf + 1e-5);
}

// The walks' first numbers from the sampler (WalkUniforms): stratified over [0, 1)² across the estimates, as a pixel's
// samples give them, both estimators still match the closed form. Each given number must serve one decision only:
// reusing the first collision's for the first event (or the roulette) correlates them and fails here.
TEST(Tracking, StratifiedFirstNumbersKeepTheEstimatorsUnbiased) {
  const int n = 32;
  VoxelGrid grid(Vec3i(n, 8, 8), Vec3(0.0f), Vec3(1.0f), false);
  for (int k = 0; k < 8; ++k)
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < n; ++i) grid.set_voxel(i, j, k, 0.5f + 6.0f * (i + 0.5f) / n);
  const float scale = 0.7f, albedo = 0.6f;
  const GridMedium m(std::move(grid), scale, Rgb(albedo), 0.0f);
  const float x0 = 0.5f / n, x1 = 1.0f - 0.5f / n;
  const Ray ray{Vec3(x0, 0.4f, 0.6f), Vec3(1, 0, 0), kInfinity};
  const float length = x1 - x0;
  const double expect = std::exp(-scale * (0.5 * (x1 - x0) + 3.0 * (x1 * x1 - x0 * x0)));
  Pcg32 rng(15);
  constexpr int kSide = 400;  // kSide² estimates, one per cell of a grid over the two first numbers
  double rt = 0, rt2 = 0, ff = 0, ff2 = 0;
  for (int a = 0; a < kSide; ++a)
    for (int b = 0; b < kSide; ++b) {
      const Vec2 first((a + rng.next_float()) / kSide, (b + rng.next_float()) / kSide);
      PathBudget budget;
      const double T = ratio_tracking(m, ray, length, WalkUniforms(rng, first), budget).g;
      rt += T;
      rt2 += T * T;
      Rgb beta(1.0f);
      float t;
      // Passing carries the null events' weights; scattering is counted as 0, so the mean is the transmittance.
      const double pass = sample_free_flight(m, ray, length, WalkUniforms(rng, first), beta, &t, budget) ? 0.0 : beta.g;
      ff += pass;
      ff2 += pass * pass;
    }
  const double count = double(kSide) * kSide;
  // The i.i.d. standard error bounds the stratified estimate's.
  const double mr = rt / count, sr = std::sqrt(std::max(0.0, rt2 / count - mr * mr) / count);
  const double mf = ff / count, sf = std::sqrt(std::max(0.0, ff2 / count - mf * mf) / count);
  EXPECT_NEAR(mr, expect, 4 * sr + 1e-5);
  EXPECT_NEAR(mf, expect, 4 * sf + 1e-5);
}

TEST(Tracking, HeterogeneousGridMatchesClosedForm) { expect_ramp_transmittance(Transform(), 13); }

TEST(Tracking, TransformedGridMatchesClosedForm) {
  // Non-uniform scale (x stretched 1.8x), an oblique rotation and a translation: T = exp(−1.8 · 0.7 ∫ρ) ≈ 0.03
  // against 0.14 untransformed, so a walk in the wrong parameterisation fails by far more than 4 s.e.
  const Transform m = Transform::translate(Vec3(3.0f, -1.0f, 2.0f)) * Transform::rotate(Vec3(0.3f, 1.0f, 0.5f), 40.0f) *
                      Transform::scale(Vec3(1.8f, 0.5f, 1.2f));
  expect_ramp_transmittance(m, 14);
}

// A medium that is empty but claims an absurd majorant (as a grid medium with density_scale 1e7 or 1e30 does
// between its dense voxels): every tentative collision is null, and with 1e30 the steps fall below float
// resolution so t never advances. The per-path budget ends both walks after PathBudget::kMaxCollisions steps
// (absorbed: beta 0, transmittance 0) and reports it; a raised stop flag ends them within 1024 steps.
class AbsurdMajorantMedium final : public Medium {
 public:
  explicit AbsurdMajorantMedium(float majorant) : majorant_(majorant) {}
  MediumProperties properties(const Vec3&, const Vec3&) const override {
    ++lookups;
    return {};
  }
  const PhaseFunction* phase(const Vec3&, Arena&) const override { return nullptr; }
  void majorants(const Vec3&, const Vec3&, float t0, float t1, MajorantVisitor& v) const override {
    v.segment(t0, t1, majorant_);
  }
  mutable uint64_t lookups = 0;

 private:
  float majorant_;
};

TEST(Tracking, PathBudgetEndsWalksThatWouldNotEnd) {
  for (float majorant : {1e7f, 1e30f}) {
    const AbsurdMajorantMedium m(majorant);
    const Ray ray{Vec3(0.0f), Vec3(1, 0, 0), kInfinity};
    Pcg32 rng(5);
    PathBudget budget;
    Rgb beta(1.0f);
    float t;
    EXPECT_FALSE(sample_free_flight(m, ray, 10.0f, rng, beta, &t, budget));
    EXPECT_EQ(beta, Rgb(0.0f));
    EXPECT_TRUE(budget.exhausted());
    EXPECT_LE(m.lookups, uint64_t{PathBudget::kMaxCollisions});
    // The budget is the path's: a shadow ray after it has none left.
    EXPECT_EQ(ratio_tracking(m, ray, 10.0f, rng, budget), Rgb(0.0f));
    EXPECT_LE(m.lookups, uint64_t{PathBudget::kMaxCollisions});
  }
  // A walk within the budget is untouched: 1e4 × 10 = 1e5 expected steps.
  const AbsurdMajorantMedium m(1e4f);
  Pcg32 rng(6);
  PathBudget budget;
  EXPECT_EQ(ratio_tracking(m, Ray{Vec3(0.0f), Vec3(1, 0, 0), kInfinity}, 10.0f, rng, budget), Rgb(1.0f));
  EXPECT_FALSE(budget.exhausted());
}

TEST(Tracking, StopFlagEndsAWalkWithin1024Steps) {
  const AbsurdMajorantMedium m(1e30f);
  StopFlag stop{true};
  PathBudget budget(&stop);
  Pcg32 rng(7);
  EXPECT_EQ(ratio_tracking(m, Ray{Vec3(0.0f), Vec3(1, 0, 0), kInfinity}, 10.0f, rng, budget), Rgb(0.0f));
  EXPECT_LE(m.lookups, 1024u);
  EXPECT_TRUE(budget.stopped());
  EXPECT_FALSE(budget.exhausted());  // stopped, not truncated: not counted as a truncated path
}

}  // namespace
}  // namespace kozu
