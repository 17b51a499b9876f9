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

// Rows [y0, y1) of the image (w × h).
struct Inputs {
  int w = 0, h = 0, y0 = 0, y1 = 0;
  size_t index(int x, int y) const { return static_cast<size_t>(y - y0) * w + x; }
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

// The rows a fit of rows [c0, c1) reads, r = 0: its tasks' rows, whole multiples of kBand (see fit).
int task_rows_begin(int c0) { return c0 / kBand * kBand; }
int task_rows_end(int c1, int h) { return std::min(h, (c1 + kBand - 1) / kBand * kBand); }

// Both halves' fits for window radius r (the demodulated values) at rows [c0, c1), index (y − c0) w + x. The tasks are
// the image's rows kBand at a time from row 0, whatever [c0, c1): the window sums slide from a task's first row, so
// any band of rows sums in the same order as the whole image, and gives the same values bit for bit. `in` must hold
// the rows [task_rows_begin(c0) − r, task_rows_end(c1) + r) within the image. False when `expired` stopped it.
bool fit(const Inputs& in, int r, float ridge, const std::function<bool()>& expired, int c0, int c1,
         std::vector<Vec3> (&out)[2]) {
  const int w = in.w, h = in.h;
  const int t0 = task_rows_begin(c0), t1 = task_rows_end(c1, h);
  if (in.y0 > std::max(0, t0 - r) || in.y1 < std::min(h, t1 + r))
    throw std::logic_error("feature regression: the inputs do not hold the rows the window reads");
  std::atomic<bool> stop{false};
  tbb::parallel_for(t0 / kBand, (t1 + kBand - 1) / kBand, [&](int band) {
    if (stop.load(std::memory_order_relaxed)) return;
    if (expired && expired()) {
      stop = true;
      return;
    }
    const int y0 = band * kBand, y1 = std::min(h, y0 + kBand);
    // Horizontal window sums of the products, a row at a time into a ring of the 2r + 2 rows the vertical window
    // needs at once (the row it adds and the one it drops): a task's every row held at once took 27 MB at 1080p
    // for r = 15.
    const int slots = 2 * r + 2;
    std::vector<float> hsum(static_cast<size_t>(slots) * w * kK);
    std::vector<float> row(static_cast<size_t>(w) * kK);
    const auto slot = [&](int y) { return &hsum[static_cast<size_t>(y % slots) * w * kK]; };
    const auto sum_row = [&](int y) {
      for (int x = 0; x < w; ++x) products(in, in.index(x, y), &row[static_cast<size_t>(x) * kK]);
      float* dst = slot(y);
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
    };
    // Vertical sliding sums, and the fit at each pixel of the band's rows.
    std::vector<float> vsum(static_cast<size_t>(w) * kK, 0.0f);
    const auto add_row = [&](int y, float sign) {
      const float* src = slot(y);
      for (size_t k = 0; k < vsum.size(); ++k) vsum[k] += sign * src[k];
    };
    for (int y = std::max(0, y0 - r); y <= std::min(h - 1, y0 + r); ++y) {
      sum_row(y);
      add_row(y, 1.0f);
    }
    for (int y = y0; y < y1; ++y) {
      const float rows = static_cast<float>(std::min(h - 1, y + r) - std::max(0, y - r) + 1);
      for (int x = 0; x < w && y >= c0 && y < c1; ++x) {  // rows outside [c0, c1) only slide the sums
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
        const size_t i = static_cast<size_t>(y - c0) * w + x;
        const Feature& fi = in.f[in.index(x, y)];
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
        if (y + r + 1 < h) {
          sum_row(y + r + 1);
          add_row(y + r + 1, 1.0f);
        }
        if (y - r >= 0) add_row(y - r, -1.0f);
      }
    }
  });
  return !stop;
}

}  // namespace

std::vector<float> denoise_regression(const Film& film, const RegressionSettings& s, const VisibleEmission* emission,
                                      const std::function<bool()>& expired, std::vector<float>* risk_out) {
  VisibleEmission own;
  const VisibleEmission& visible = emission_to_add_back(film, emission, own, "denoise_regression");
  const int w = film.width(), h = film.height();
  const size_t n = film.pixels().size();
  std::vector<float> out(3 * n, 0.0f);
  if (risk_out) risk_out->assign(n, 0.0f);
  if (n == 0) return out;
  const int R = std::max(0, s.risk_radius);
  int reach = 0;  // the widest window
  for (const int r : s.radii) reach = std::max(reach, r);
  // Bands of rows, each with the rows its windows and risk boxes read: memory in proportion to a band, not to the
  // image, and the same pixels bit for bit (fit's tasks are the whole image's).
  const int band = s.band_rows > 0 ? s.band_rows : 192;
  const HalfBufferRows half_buffers(film, visible);
  bool stopped = false;  // past the deadline: this band keeps the windows it finished, the bands after the pixel alone
  for (int y0 = 0; y0 < h; y0 += band) {
    const int y1 = std::min(h, y0 + band);
    const int c0 = std::max(0, y0 - R), c1 = std::min(h, y1 + R);  // the candidates' rows the risk boxes read
    const size_t m = static_cast<size_t>(w) * (c1 - c0);
    Buffers b = half_buffers.rows(task_rows_begin(c0) - reach, task_rows_end(c1, h) + reach);
    Inputs in;
    in.w = w;
    in.h = h;
    in.y0 = b.y0;
    in.y1 = b.y1;
    const size_t nb = b.half[0].size();
    in.f.resize(nb);
    in.scale.resize(nb);
    for (auto& y : in.y) y.resize(nb);
    for (size_t i = 0; i < nb; ++i) {
      const float z = b.depth[i];
      const Vec3& a = b.albedo[i];
      in.f[i] = {b.normal[i].x, b.normal[i].y, b.normal[i].z, std::isfinite(z) && z > 0.0f ? std::log(z) : kMissDepth,
                 0.2126f * a.x + 0.7152f * a.y + 0.0722f * a.z};
      in.scale[i] = glm::max(b.albedo[i], Vec3(0.0f)) + s.albedo_floor;
      for (int k = 0; k < 2; ++k) in.y[k][i] = b.half[k][i] / in.scale[i];
    }
    // The features are in `in` now: 28 bytes a pixel of the band freed.
    std::vector<Vec3>().swap(b.albedo);
    std::vector<Vec3>().swap(b.normal);
    std::vector<float>().swap(b.depth);
    // The candidates' rows [c0, c1): index i = (y − c0) w + x; p, the same pixel in the buffers.
    const size_t p0 = b.index(0, c0);
    // Radius 0 first: the pixel itself, whose estimated error is the variance of the two halves' mean.
    std::vector<Vec3> best(m);                      // the blend's running weighted sum
    std::vector<float> best_risk, weight(m, 1.0f);  // the least risk so far, and the blend's weight sum against it
    std::vector<float> e(m);
    for (size_t i = 0; i < m; ++i) {
      const size_t p = p0 + i;
      best[i] = 0.5f * (b.half[0][p] + b.half[1][p]);
      const Vec3 d = b.half[0][p] - b.half[1][p];
      e[i] = std::min(glm::dot(d, d) / 3.0f - b.var[p], kUnknownVariance);
    }
    best_risk = box_mean(e, w, c1 - c0, R);
    // The blend's temperature per pixel: τ times the noise variance averaged over the risk's box.
    std::vector<float> temperature =
        box_mean(std::vector<float>(b.var.begin() + static_cast<ptrdiff_t>(p0),
                                    b.var.begin() + static_cast<ptrdiff_t>(p0 + m)),
                 w, c1 - c0, R);
    for (float& t : temperature) t = std::max(s.softness * std::min(t, kUnknownVariance), 1e-20f);
    std::vector<Vec3> fits[2] = {std::vector<Vec3>(m), std::vector<Vec3>(m)};
    for (const int r : s.radii) {
      if (r <= 0) continue;
      if (stopped || !fit(in, r, s.ridge, expired, c0, c1, fits)) {
        stopped = true;
        break;
      }
      for (size_t i = 0; i < m; ++i) {
        const size_t p = p0 + i;
        const Vec3 fa = fits[0][i] * in.scale[p], fb = fits[1][i] * in.scale[p];
        const Vec3 da = fa - b.half[1][p], db = fb - b.half[0][p];
        e[i] = std::min(0.5f * (glm::dot(da, da) + glm::dot(db, db)) / 3.0f - b.var[p], kUnknownVariance);
      }
      const std::vector<float> risk = box_mean(e, w, c1 - c0, R);
      for (size_t i = 0; i < m; ++i) {
        const Vec3 candidate = 0.5f * (fits[0][i] + fits[1][i]) * in.scale[p0 + i];
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
            const float wt = std::exp(-(risk[i] - best_risk[i]) / temperature[i]);
            best[i] += wt * candidate;
            weight[i] += wt;
          }
        }
      }
    }
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = static_cast<size_t>(y - c0) * w + x;
        put_pixel(out, static_cast<size_t>(y) * w + x, best[i] / weight[i], visible);
        if (risk_out) (*risk_out)[static_cast<size_t>(y) * w + x] = best_risk[i];
      }
  }
  return out;
}

}  // namespace kozu
