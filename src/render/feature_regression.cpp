#include "render/feature_regression.h"

#include "render/denoise_buffers.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <stdexcept>

namespace kozu {

namespace {

using namespace denoise_detail;

constexpr int kP = 5;                          // features: normal (3), log depth, albedo luminance
constexpr int kPP = kP * (kP + 1) / 2;         // their products (upper triangle)
constexpr int kK = kP + kPP + 6 + 2 * 3 * kP;  // window sums: f, f fᵀ, y_A, y_B, f y_Aᵀ, f y_Bᵀ
constexpr int kBand = 32;                      // rows per task
constexpr float kMissDepth = 20.0f;            // log depth of a pixel that saw nothing (the sky, a miss)

using Feature = std::array<float, kP>;

struct Inputs {
  int w = 0, h = 0;
  std::vector<Feature> f;
  std::vector<Vec3> y[2];   // demodulated halves
  std::vector<Vec3> scale;  // albedo + ε, multiplied back
};

// The per-pixel products whose window sums the fit needs, in the order of kK.
inline void products(const Inputs& in, size_t i, float* c) {
  const Feature& f = in.f[i];
  int k = 0;
  for (int a = 0; a < kP; ++a) c[k++] = f[a];
  for (int a = 0; a < kP; ++a)
    for (int b = a; b < kP; ++b) c[k++] = f[a] * f[b];
  for (int h = 0; h < 2; ++h)
    for (int ch = 0; ch < 3; ++ch) c[k++] = in.y[h][i][ch];
  for (int h = 0; h < 2; ++h)
    for (int a = 0; a < kP; ++a)
      for (int ch = 0; ch < 3; ++ch) c[k++] = f[a] * in.y[h][i][ch];
}

// Solves (C + λ I) x = rhs for the kP × kP symmetric C given as its upper triangle, by Cholesky; 6 right-hand
// sides (3 colour channels of 2 halves) in rhs[kP][6], overwritten by the solution. False when not positive definite.
bool solve(std::array<float, kPP> c, float ridge, std::array<std::array<float, 6>, kP>& rhs) {
  float L[kP][kP] = {};
  float A[kP][kP];
  int k = 0;
  for (int a = 0; a < kP; ++a)
    for (int b = a; b < kP; ++b, ++k) A[a][b] = A[b][a] = c[static_cast<size_t>(k)];
  for (int a = 0; a < kP; ++a) A[a][a] += ridge;
  for (int j = 0; j < kP; ++j) {
    float d = A[j][j];
    for (int t = 0; t < j; ++t) d -= L[j][t] * L[j][t];
    if (!(d > 0.0f)) return false;
    L[j][j] = std::sqrt(d);
    for (int i = j + 1; i < kP; ++i) {
      float s = A[i][j];
      for (int t = 0; t < j; ++t) s -= L[i][t] * L[j][t];
      L[i][j] = s / L[j][j];
    }
  }
  for (int r = 0; r < 6; ++r) {
    float z[kP];
    for (int i = 0; i < kP; ++i) {
      float s = rhs[static_cast<size_t>(i)][static_cast<size_t>(r)];
      for (int t = 0; t < i; ++t) s -= L[i][t] * z[t];
      z[i] = s / L[i][i];
    }
    for (int i = kP - 1; i >= 0; --i) {
      float s = z[i];
      for (int t = i + 1; t < kP; ++t) s -= L[t][i] * rhs[static_cast<size_t>(t)][static_cast<size_t>(r)];
      rhs[static_cast<size_t>(i)][static_cast<size_t>(r)] = s / L[i][i];
    }
  }
  return true;
}

// Both halves' fits at every pixel for window radius r (the demodulated values); false when `expired` stopped it.
bool fit(const Inputs& in, int r, float ridge, const std::function<bool()>& expired, std::vector<Vec3> (&out)[2]) {
  const int w = in.w, h = in.h;
  std::atomic<bool> stop{false};
  tbb::parallel_for(0, (h + kBand - 1) / kBand, [&](int band) {
    if (stop.load(std::memory_order_relaxed)) return;
    if (expired && expired()) {
      stop = true;
      return;
    }
    const int y0 = band * kBand, y1 = std::min(h, y0 + kBand);
    const int ry0 = std::max(0, y0 - r), ry1 = std::min(h, y1 + r);
    // Horizontal window sums of the products, rows ry0..ry1-1.
    std::vector<float> hsum(static_cast<size_t>(ry1 - ry0) * w * kK);
    std::vector<float> row(static_cast<size_t>(w) * kK);
    for (int y = ry0; y < ry1; ++y) {
      for (int x = 0; x < w; ++x) products(in, static_cast<size_t>(y) * w + x, &row[static_cast<size_t>(x) * kK]);
      float* dst = &hsum[static_cast<size_t>(y - ry0) * w * kK];
      float acc[kK] = {};
      for (int x = 0; x <= std::min(w - 1, r); ++x)
        for (int k = 0; k < kK; ++k) acc[k] += row[static_cast<size_t>(x) * kK + k];
      for (int x = 0; x < w; ++x) {
        std::copy(acc, acc + kK, dst + static_cast<size_t>(x) * kK);
        const int add = x + r + 1, sub = x - r;
        if (add < w)
          for (int k = 0; k < kK; ++k) acc[k] += row[static_cast<size_t>(add) * kK + k];
        if (sub >= 0)
          for (int k = 0; k < kK; ++k) acc[k] -= row[static_cast<size_t>(sub) * kK + k];
      }
    }
    // Vertical sliding sums, and the fit at each pixel of the band's rows.
    std::vector<float> vsum(static_cast<size_t>(w) * kK, 0.0f);
    const auto add_row = [&](int y, float sign) {
      const float* src = &hsum[static_cast<size_t>(y - ry0) * w * kK];
      for (size_t k = 0; k < vsum.size(); ++k) vsum[k] += sign * src[k];
    };
    for (int y = std::max(0, y0 - r); y <= std::min(h - 1, y0 + r); ++y) add_row(y, 1.0f);
    for (int y = y0; y < y1; ++y) {
      const float rows = static_cast<float>(std::min(h - 1, y + r) - std::max(0, y - r) + 1);
      for (int x = 0; x < w; ++x) {
        const float n = rows * static_cast<float>(std::min(w - 1, x + r) - std::max(0, x - r) + 1);
        const float inv = 1.0f / n;
        const float* s = &vsum[static_cast<size_t>(x) * kK];
        float mf[kP];
        for (int a = 0; a < kP; ++a) mf[a] = s[a] * inv;
        std::array<float, kPP> cov{};
        int k = 0;
        for (int a = 0; a < kP; ++a)
          for (int b = a; b < kP; ++b, ++k) cov[static_cast<size_t>(k)] = s[kP + k] * inv - mf[a] * mf[b];
        float my[6];
        for (int c = 0; c < 6; ++c) my[c] = s[kP + kPP + c] * inv;
        std::array<std::array<float, 6>, kP> rhs{};
        for (int hf = 0; hf < 2; ++hf)
          for (int a = 0; a < kP; ++a)
            for (int c = 0; c < 3; ++c)
              rhs[static_cast<size_t>(a)][static_cast<size_t>(3 * hf + c)] =
                  s[kP + kPP + 6 + hf * 3 * kP + 3 * a + c] * inv - mf[a] * my[3 * hf + c];
        const size_t i = static_cast<size_t>(y) * w + x;
        const Feature& fi = in.f[i];
        if (!solve(cov, ridge, rhs)) {
          for (int hf = 0; hf < 2; ++hf) out[hf][i] = Vec3(my[3 * hf], my[3 * hf + 1], my[3 * hf + 2]);
          continue;
        }
        for (int hf = 0; hf < 2; ++hf) {
          Vec3 v(my[3 * hf], my[3 * hf + 1], my[3 * hf + 2]);
          for (int a = 0; a < kP; ++a)
            for (int c = 0; c < 3; ++c)
              v[c] +=
                  rhs[static_cast<size_t>(a)][static_cast<size_t>(3 * hf + c)] * (fi[static_cast<size_t>(a)] - mf[a]);
          out[hf][i] = v;
        }
      }
      if (y + 1 < y1) {
        if (y + r + 1 < h) add_row(y + r + 1, 1.0f);
        if (y - r >= 0) add_row(y - r, -1.0f);
      }
    }
  });
  return !stop;
}

}  // namespace

std::vector<float> denoise_regression(const Film& film, const RegressionSettings& s, const VisibleEmission* emission,
                                      const std::function<bool()>& expired) {
  VisibleEmission own;
  const VisibleEmission& visible = emission_to_add_back(film, emission, own, "denoise_regression");
  const size_t n = film.pixels().size();
  const Buffers b = split(film, visible);
  std::vector<float> out(3 * n, 0.0f);
  if (n == 0) return out;
  Inputs in;
  in.w = b.w;
  in.h = b.h;
  in.f.resize(n);
  in.scale.resize(n);
  for (auto& y : in.y) y.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const float z = b.depth[i];
    const Vec3& a = b.albedo[i];
    in.f[i] = {b.normal[i].x, b.normal[i].y, b.normal[i].z, std::isfinite(z) && z > 0.0f ? std::log(z) : kMissDepth,
               0.2126f * a.x + 0.7152f * a.y + 0.0722f * a.z};
    in.scale[i] = glm::max(b.albedo[i], Vec3(0.0f)) + s.albedo_floor;
    for (int k = 0; k < 2; ++k) in.y[k][i] = b.half[k][i] / in.scale[i];
  }
  // Radius 0 first: the pixel itself, whose estimated error is the variance of the two halves' mean.
  std::vector<Vec3> best(n);                      // the blend's running weighted sum
  std::vector<float> best_risk, weight(n, 1.0f);  // the least risk so far, and the blend's weight sum against it
  {
    std::vector<float> e(n);
    for (size_t i = 0; i < n; ++i) {
      best[i] = 0.5f * (b.half[0][i] + b.half[1][i]);
      const Vec3 d = b.half[0][i] - b.half[1][i];
      e[i] = std::min(glm::dot(d, d) / 3.0f - b.var[i], kUnknownVariance);
    }
    best_risk = box_mean(e, b.w, b.h, std::max(0, s.risk_radius));
  }
  // The blend's temperature per pixel: τ times the noise variance averaged over the risk's box.
  std::vector<float> temperature = box_mean(b.var, b.w, b.h, std::max(0, s.risk_radius));
  for (float& t : temperature) t = std::max(s.softness * std::min(t, kUnknownVariance), 1e-20f);
  std::vector<Vec3> fits[2] = {std::vector<Vec3>(n), std::vector<Vec3>(n)};
  for (const int r : s.radii) {
    if (r <= 0) continue;
    if (!fit(in, r, s.ridge, expired, fits)) break;
    std::vector<float> e(n);
    for (size_t i = 0; i < n; ++i) {
      const Vec3 fa = fits[0][i] * in.scale[i], fb = fits[1][i] * in.scale[i];
      const Vec3 da = fa - b.half[1][i], db = fb - b.half[0][i];
      e[i] = std::min(0.5f * (glm::dot(da, da) + glm::dot(db, db)) / 3.0f - b.var[i], kUnknownVariance);
    }
    const std::vector<float> risk = box_mean(e, b.w, b.h, std::max(0, s.risk_radius));
    for (size_t i = 0; i < n; ++i) {
      const Vec3 candidate = 0.5f * (fits[0][i] + fits[1][i]) * in.scale[i];
      if (!s.select || (s.softness <= 0.0f && risk[i] < best_risk[i])) {
        best_risk[i] = risk[i];
        best[i] = candidate;
        weight[i] = 1.0f;
      } else if (s.softness > 0.0f) {
        // exp(−(risk − least) / T), the sum rescaled when this candidate is the new least.
        if (risk[i] < best_risk[i]) {
          const float rescale = std::exp(-(best_risk[i] - risk[i]) / temperature[i]);
          best[i] = best[i] * rescale + candidate;
          weight[i] = weight[i] * rescale + 1.0f;
          best_risk[i] = risk[i];
        } else {
          const float w = std::exp(-(risk[i] - best_risk[i]) / temperature[i]);
          best[i] += w * candidate;
          weight[i] += w;
        }
      }
    }
  }
  for (size_t i = 0; i < n; ++i) {
    put_pixel(out, i, best[i] / weight[i], visible);
  }
  return out;
}

}  // namespace kozu
