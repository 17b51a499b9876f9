#include "render/denoiser.h"

#include "render/denoise_buffers.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <functional>
#include <stdexcept>

namespace kozu {

namespace {

using namespace denoise_detail;

// The loops over a row's pixels read planes through pointers the compiler cannot prove apart; they are (each
// writes its own buffer). GCC 12 vectorizes none of them with local __restrict pointers, all with this.
#if defined(__clang__)
#if __has_feature(address_sanitizer)
#define KOZU_IVDEP  // instrumented loads do not vectorize: the hint would only warn (-Wpass-failed)
#else
#define KOZU_IVDEP _Pragma("clang loop vectorize(assume_safety)")
#endif
#elif defined(__GNUC__)
#define KOZU_IVDEP _Pragma("GCC ivdep")
#else
#define KOZU_IVDEP
#endif

constexpr int kBand = 16;   // rows per task of nl_means
constexpr int kTile = 256;  // columns per task of nl_means

// Each half buffer filtered with window radius r (and the other half's colour weights), and the share of the
// pixel's own weight in its sum: ∂F_k(p)/∂y_k(p), since the weights do not depend on y_k (SURE, below).
struct Filtered {
  std::vector<Vec3> half[2];
  std::vector<float> self[2];
};

// A film's half buffers and features as planes of floats (structure of arrays), so that the filter's loops over a
// row vectorize; built from Buffers one field at a time, freeing each as it goes (the peak grows by one field).
struct Planes {
  int w = 0, h = 0, y0 = 0, y1 = 0;
  size_t index(int x, int y) const { return static_cast<size_t>(y - y0) * w + x; }
  std::vector<float> c[2][3];  // half k's channel
  std::vector<float> var;
  std::vector<float> f[6];  // albedo / σ_albedo and normal / σ_normal: the feature terms are their squared differences
  std::vector<float> z;     // depth
};

Planes planes(Buffers&& b, const DenoiseSettings& s) {
  Planes p;
  p.w = b.w;
  p.h = b.h;
  p.y0 = b.y0;
  p.y1 = b.y1;
  const size_t n = b.var.size();
  const auto split3 = [n](std::vector<Vec3>& v, std::vector<float>* out, float scale) {
    for (int c = 0; c < 3; ++c) {
      out[c].resize(n);
      for (size_t i = 0; i < n; ++i) out[c][i] = v[i][c] * scale;
    }
    std::vector<Vec3>().swap(v);
  };
  split3(b.half[0], p.c[0], 1.0f);
  split3(b.half[1], p.c[1], 1.0f);
  split3(b.albedo, p.f, 1.0f / s.sigma_albedo);
  split3(b.normal, p.f + 3, 1.0f / s.sigma_normal);
  p.var = std::move(b.var);
  p.z = std::move(b.depth);
  return p;
}

// e^{−x} for x ≥ 0 (NaN excepted), inlined so that the filter's loops vectorize (std::exp is a call; it took a quarter
// of the filter's time): x = n ln 2 + r with n the nearest integer, |r| ≤ ln 2 / 2 (ln 2 in two parts, Cody & Waite),
// e^{−r} by its Taylor series to r⁶ (truncation below 0.35⁷ / 7! ≈ 1.3·10⁻⁷), 2^{−n} from the exponent's bits; x is
// clamped to 87, where e^{−x} ≈ 1.6·10⁻³⁸ is still a normal float.
inline float exp_neg(float x) {
  x = std::min(x, 87.0f);
  const float n = std::nearbyint(x * 1.44269504f);  // (std::floor does not vectorize under GCC 12)
  const float r = -((x - n * 0.693359375f) + n * 2.12194440e-4f);
  const float e =
      1.0f +
      r * (1.0f + r * (0.5f + r * (1.0f / 6.0f + r * (1.0f / 24.0f + r * (1.0f / 120.0f + r * (1.0f / 720.0f))))));
  return e * std::bit_cast<float>((127 - static_cast<int32_t>(n)) << 23);
}

// Rows [c0, c1) of the image, index (y − c0) w + x; b must hold every row they read, [c0 − r − f, c1 + r + f) within
// the image. `expired` (optional) is polled before each task; once it says true the rest is skipped and `stopped`
// set.
Filtered nl_means(const Planes& b, const DenoiseSettings& s, int r, int c0, int c1,
                  const std::function<bool()>& expired = {}, std::atomic<bool>* stopped = nullptr) {
  const int w = b.w, h = b.h, f = std::max(0, s.patch);
  if (b.y0 > std::max(0, c0 - r - f) || b.y1 < std::min(h, c1 + r + f))
    throw std::logic_error("nl_means: the buffers do not hold the rows the window reads");
  const size_t n = static_cast<size_t>(w) * (c1 - c0);
  Filtered out;
  for (int k = 0; k < 2; ++k) {
    out.half[k].resize(n);
    out.self[k].resize(n);
  }
  const float k2 = s.k * s.k, inv_sigma_z = 1.0f / s.sigma_depth, inv_patch = 1.0f / static_cast<float>(2 * f + 1);
  constexpr float kEps = 1e-10f;
  constexpr float kOutside = 1e30f;  // a patch pixel whose neighbour lies outside the image: weight 0
  // A neighbour whose feature weight exp(−fd) is at most 10⁻⁶ is left out.
  constexpr float kMaxFeatureDistance = 13.8155106f;
  const int bands = (c1 - c0 + kBand - 1) / kBand, tiles = (w + kTile - 1) / kTile;
  // Tasks of kBand rows × kTile columns in parallel (a task's sums and the rows it reads stay in cache); each
  // computes, per offset, the per-pixel distances of its patches' pixels, box-filters them along x and then y, and
  // accumulates. Every loop over x vectorizes; a pixel's result does not depend on the task that holds it.
  tbb::parallel_for(0, bands * tiles, [&](int task) {
    if (stopped && (stopped->load(std::memory_order_relaxed) || (expired && expired()))) {
      *stopped = true;
      return;
    }
    const int y0 = c0 + task / tiles * kBand, y1 = std::min(c1, y0 + kBand);
    const int x0 = task % tiles * kTile, x1 = std::min(w, x0 + kTile);
    const int ry0 = std::max(0, y0 - f), ry1 = std::min(h, y1 + f);  // rows and columns the patches read
    const int rx0 = std::max(0, x0 - f), rx1 = std::min(w, x1 + f);
    const int rows = ry1 - ry0, cols = rx1 - rx0, ow = x1 - x0, oh = y1 - y0;
    std::vector<float> dist[2], rowsum[2], patch[2], num[2][3], den[2];
    for (int k = 0; k < 2; ++k) {
      dist[k].resize(static_cast<size_t>(rows) * cols);
      rowsum[k].resize(static_cast<size_t>(rows) * ow);
      patch[k].resize(ow);
      for (auto& v : num[k]) v.assign(static_cast<size_t>(oh) * ow, 0.0f);
      den[k].assign(static_cast<size_t>(oh) * ow, 0.0f);
    }
    // 1 / (σ_z z_p), the relative depth difference's scale.
    std::vector<float> inv_z(static_cast<size_t>(oh) * ow);
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x)
        inv_z[static_cast<size_t>(y - y0) * ow + (x - x0)] =
            inv_sigma_z / std::max(std::abs(b.z[b.index(x, y)]), 1e-6f);
    // Every loop below runs over i = 0 .. n − 1 from pointers to the first element it touches, so that no pointer
    // leaves its buffer (a row's start minus an offset is undefined behaviour, and UBSan reports the wrap-around).
    for (int dy = -r; dy <= r; ++dy)
      for (int dx = -r; dx <= r; ++dx) {
        // Per-pixel colour distance of each half buffer to its neighbour at (dx, dy), columns [rx0, rx1).
        for (int y = ry0; y < ry1; ++y) {
          float* d0 = dist[0].data() + static_cast<size_t>(y - ry0) * cols;  // column rx0
          float* d1 = dist[1].data() + static_cast<size_t>(y - ry0) * cols;
          const int qy = y + dy;
          const bool row_in = qy >= 0 && qy < h;
          const int xa = row_in ? std::clamp(-dx, rx0, rx1) : rx1, xb = row_in ? std::clamp(w - dx, xa, rx1) : rx1;
          for (int x = rx0; x < xa; ++x) d0[x - rx0] = d1[x - rx0] = kOutside;
          for (int x = xb; x < rx1; ++x) d0[x - rx0] = d1[x - rx0] = kOutside;
          if (xa >= xb) continue;
          // Pixel xa of row y and its neighbour xa + dx of row qy.
          const size_t p = b.index(xa, y), q = b.index(xa + dx, qy);
          const float *vp = b.var.data() + p, *vq = b.var.data() + q;
          const float *a0 = b.c[0][0].data() + p, *a1 = b.c[0][1].data() + p, *a2 = b.c[0][2].data() + p;
          const float *b0 = b.c[1][0].data() + p, *b1 = b.c[1][1].data() + p, *b2 = b.c[1][2].data() + p;
          const float *qa0 = b.c[0][0].data() + q, *qa1 = b.c[0][1].data() + q, *qa2 = b.c[0][2].data() + q;
          const float *qb0 = b.c[1][0].data() + q, *qb1 = b.c[1][1].data() + q, *qb2 = b.c[1][2].data() + q;
          float *e0 = d0 + (xa - rx0), *e1 = d1 + (xa - rx0);
          const int n_x = xb - xa;
          KOZU_IVDEP
          for (int i = 0; i < n_x; ++i) {
            const float Vp = vp[i], Vq = vq[i];
            const float scale = 1.0f / (kEps + k2 * (Vp + Vq)), cancel = Vp + std::min(Vp, Vq);
            const float ea = sqr(a0[i] - qa0[i]) + sqr(a1[i] - qa1[i]) + sqr(a2[i] - qa2[i]);
            const float eb = sqr(b0[i] - qb0[i]) + sqr(b1[i] - qb1[i]) + sqr(b2[i] - qb2[i]);
            e0[i] = (ea * (1.0f / 3.0f) - cancel) * scale;
            e1[i] = (eb * (1.0f / 3.0f) - cancel) * scale;
          }
        }
        // Their mean over the patch's columns (clipped to the image), for the output's columns [x0, x1).
        const int xi0 = std::clamp(f, x0, x1), xi1 = std::clamp(w - f, xi0, x1);  // whole patches
        for (int k = 0; k < 2; ++k)
          for (int y = 0; y < rows; ++y) {
            const float* d = dist[k].data() + static_cast<size_t>(y) * cols;  // column rx0
            float* o = rowsum[k].data() + static_cast<size_t>(y) * ow;        // column x0
            const auto clipped = [&](int x) {
              float sum = 0.0f;
              const int t0 = std::max(0, x - f), t1 = std::min(w - 1, x + f);
              for (int t = t0; t <= t1; ++t) sum += d[t - rx0];
              o[x - x0] = sum / static_cast<float>(t1 - t0 + 1);
            };
            for (int x = x0; x < xi0; ++x) clipped(x);
            // Summed a column of the patch at a time, so that the loops over x vectorize.
            const int n_x = xi1 - xi0;
            float* oi = o + (xi0 - x0);
            KOZU_IVDEP
            for (int i = 0; i < n_x; ++i) oi[i] = d[xi0 - f - rx0 + i];
            for (int t = 1 - f; t <= f; ++t) {
              const float* dt = d + (xi0 + t - rx0);
              KOZU_IVDEP
              for (int i = 0; i < n_x; ++i) oi[i] += dt[i];
            }
            KOZU_IVDEP
            for (int i = 0; i < n_x; ++i) oi[i] *= inv_patch;
            for (int x = xi1; x < x1; ++x) clipped(x);
          }
        for (int y = y0; y < y1; ++y) {
          const int qy = y + dy;
          if (qy < 0 || qy >= h) continue;
          const int xa = std::clamp(-dx, x0, x1), xb = std::clamp(w - dx, xa, x1);
          if (xa >= xb) continue;
          const int n_x = xb - xa;
          // The patch's mean along y (clipped to the image), columns [xa, xb).
          const int t0 = std::max(ry0, y - f), t1 = std::min(ry1 - 1, y + f);
          const float inv_rows = 1.0f / static_cast<float>(t1 - t0 + 1);
          for (int k = 0; k < 2; ++k) {
            float* pk = patch[k].data() + (xa - x0);
            const float* first = rowsum[k].data() + static_cast<size_t>(t0 - ry0) * ow + (xa - x0);
            for (int i = 0; i < n_x; ++i) pk[i] = first[i];
            for (int t = t0 + 1; t <= t1; ++t) {
              const float* rt = rowsum[k].data() + static_cast<size_t>(t - ry0) * ow + (xa - x0);
              KOZU_IVDEP
              for (int i = 0; i < n_x; ++i) pk[i] += rt[i];
            }
            for (int i = 0; i < n_x; ++i) pk[i] *= inv_rows;
          }
          // Pixel xa of row y, its neighbour xa + dx of row qy, and its place in the task's sums.
          const size_t p = b.index(xa, y), q = b.index(xa + dx, qy),
                       o = static_cast<size_t>(y - y0) * ow + static_cast<size_t>(xa - x0);
          const float *pa = patch[0].data() + (xa - x0), *pb = patch[1].data() + (xa - x0), *iz = inv_z.data() + o;
          const float *zp = b.z.data() + p, *zq = b.z.data() + q;
          const float *f0 = b.f[0].data() + p, *f1 = b.f[1].data() + p, *f2 = b.f[2].data() + p,
                      *f3 = b.f[3].data() + p, *f4 = b.f[4].data() + p, *f5 = b.f[5].data() + p;
          const float *g0 = b.f[0].data() + q, *g1 = b.f[1].data() + q, *g2 = b.f[2].data() + q,
                      *g3 = b.f[3].data() + q, *g4 = b.f[4].data() + q, *g5 = b.f[5].data() + q;
          const float *qa0 = b.c[0][0].data() + q, *qa1 = b.c[0][1].data() + q, *qa2 = b.c[0][2].data() + q;
          const float *qb0 = b.c[1][0].data() + q, *qb1 = b.c[1][1].data() + q, *qb2 = b.c[1][2].data() + q;
          float *na0 = num[0][0].data() + o, *na1 = num[0][1].data() + o, *na2 = num[0][2].data() + o;
          float *nb0 = num[1][0].data() + o, *nb1 = num[1][1].data() + o, *nb2 = num[1][2].data() + o;
          float *da = den[0].data() + o, *db = den[1].data() + o;
          KOZU_IVDEP
          for (int i = 0; i < n_x; ++i) {
            const float dz = (zp[i] - zq[i]) * iz[i];
            const float fd = sqr(f0[i] - g0[i]) + sqr(f1[i] - g1[i]) + sqr(f2[i] - g2[i]) + sqr(f3[i] - g3[i]) +
                             sqr(f4[i] - g4[i]) + sqr(f5[i] - g5[i]) + dz * dz;
            const bool near = fd < kMaxFeatureDistance;
            // Half A takes the weights of B's colours, and B those of A's.
            const float wa = near ? exp_neg(fd + std::max(0.0f, pb[i])) : 0.0f;
            const float wb = near ? exp_neg(fd + std::max(0.0f, pa[i])) : 0.0f;
            na0[i] += wa * qa0[i];
            na1[i] += wa * qa1[i];
            na2[i] += wa * qa2[i];
            da[i] += wa;
            nb0[i] += wb * qb0[i];
            nb1[i] += wb * qb1[i];
            nb2[i] += wb * qb2[i];
            db[i] += wb;
          }
        }
      }
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) {
        const size_t o = static_cast<size_t>(y - y0) * ow + (x - x0), p = b.index(x, y),
                     c = static_cast<size_t>(y - c0) * w + x;
        for (int k = 0; k < 2; ++k) {
          // The pixel itself always takes weight 1 (distance 0, identical features).
          const Vec3 own(b.c[k][0][p], b.c[k][1][p], b.c[k][2][p]);
          const Vec3 sum(num[k][0][o], num[k][1][o], num[k][2][o]);
          out.half[k][c] = den[k][o] > 0.0f ? sum / den[k][o] : own;
          out.self[k][c] = den[k][o] > 0.0f ? 1.0f / den[k][o] : 1.0f;
        }
      }
  });
  return out;
}

// A candidate's output (the mean of its two halves) and its estimated squared error per pixel: Stein's unbiased risk
// estimate from both halves, |F_k − y_k|² − V + 2 V ∂F_k/∂y_k, averaged over the (2R + 1)² box.
struct Scored {
  std::vector<Vec3> mean;
  std::vector<float> risk;
};

Scored score(Filtered&& c, const Planes& b, int c0, int c1, int R) {
  const int w = b.w;
  Scored out;
  std::vector<float> sure(static_cast<size_t>(w) * (c1 - c0));
  out.mean.resize(sure.size());
  for (int y = c0; y < c1; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y - c0) * w + x, p = b.index(x, y);
      float e = 0.0f;
      for (int k = 0; k < 2; ++k) {
        const Vec3 d = c.half[k][i] - Vec3(b.c[k][0][p], b.c[k][1][p], b.c[k][2][p]);
        e += glm::dot(d, d) / 3.0f - b.var[p] + 2.0f * b.var[p] * c.self[k][i];
      }
      sure[i] = std::min(0.5f * e, kUnknownVariance);
      out.mean[i] = 0.5f * (c.half[0][i] + c.half[1][i]);
    }
  c = Filtered{};  // its halves are not needed for the box
  out.risk = box_mean(sure, w, c1 - c0, R);
  return out;
}

}  // namespace

std::vector<float> denoise(const Film& film, const DenoiseSettings& s, const VisibleEmission* emission,
                           const std::function<bool()>& expired, std::vector<float>* risk) {
  VisibleEmission own;
  const VisibleEmission& visible = emission_to_add_back(film, emission, own, "denoise");
  const int w = film.width(), h = film.height();
  const size_t n = film.pixels().size();
  std::vector<float> out(3 * n, 0.0f);
  if (risk) risk->assign(n, 0.0f);
  if (n == 0) return out;
  const int r = std::max(0, s.radius), r_small = std::max(0, s.radius_small), R = std::max(0, s.risk_radius);
  const int reach = std::max(r, r_small) + std::max(0, s.patch);  // rows a candidate row reads beyond itself
  // Bands of rows, each with the rows its windows, patches and risk boxes read: memory in proportion to a band, not
  // to the image (a 1080p film's full-image buffers were 2.8 times the render's memory), the same pixels bit for bit.
  // Each band's candidates span its rows and R more either side, in tasks of kBand rows: bands of at least 192 rows
  // (24 per thread), sized so that those rows fill whole tasks, keep the extra work near 5 % (bands of 128 rows cost
  // 20 % more time: their halos, and tasks half full; at 1080p on 2 threads bands of 184 rows instead of 216 took
  // 8 MB less and no more time).
  int band = s.band_rows;
  if (band <= 0) {
    const int target = std::max(192, 24 * tbb::this_task_arena::max_concurrency());
    const int bands = (h + target - 1) / target;
    band = ((h + bands - 1) / bands + 2 * R + kBand - 1) / kBand * kBand - 2 * R;
  }
  const HalfBufferRows half_buffers(film, visible);
  std::atomic<bool> stopped{false};
  for (int y0 = 0; y0 < h; y0 += band) {
    const int y1 = std::min(h, y0 + band);
    const int c0 = std::max(0, y0 - R), c1 = std::min(h, y1 + R);  // the candidates' rows the risk boxes read
    const Planes b = planes(half_buffers.rows(c0 - reach, c1 + reach), s);
    // Two windows: the wide one smooths flat regions best, the narrow one keeps what the wide one would blur
    // (reflections, shading detail that features do not show); each pixel takes the one with the lower risk.
    // The narrow window first (a twentieth of the wide one's cost): past the deadline it is the output, here and in
    // the bands after. Each candidate is scored as soon as it is made and only its mean and risk kept (16 bytes a
    // pixel instead of its 32).
    Scored scored[2];
    scored[1] = score(nl_means(b, s, r_small, c0, c1), b, c0, c1, R);
    bool wide = false;
    if (!stopped) {
      Filtered c = nl_means(b, s, r, c0, c1, expired, &stopped);
      if (!stopped) {
        scored[0] = score(std::move(c), b, c0, c1, R);
        wide = true;
      }
    }
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = static_cast<size_t>(y - c0) * w + x;
        const int best = !wide || scored[1].risk[i] < scored[0].risk[i] ? 1 : 0;
        put_pixel(out, static_cast<size_t>(y) * w + x, scored[best].mean[i], visible);
        if (risk) (*risk)[static_cast<size_t>(y) * w + x] = scored[best].risk[i];
      }
  }
  return out;
}

}  // namespace kozu
