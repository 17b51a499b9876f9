#include "textures/height_from_normals.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace kozu {
namespace {

// One level of the Poisson problem L h = f on a w x h torus, L h = 4 h - (sum of the four neighbours): the normal
// equations of the least-squares misfit over the texel edges. f = -div of the edge targets.
struct Level {
  int w = 0, h = 0;
  std::vector<double> f, u;
  size_t size() const { return size_t(w) * size_t(h); }
};

inline int wrap(int i, int n) { return i < 0 ? i + n : (i >= n ? i - n : i); }

double neighbour_sum(const Level& l, int x, int y) {
  const double* u = l.u.data();
  const size_t row = size_t(y) * l.w;
  return u[row + wrap(x - 1, l.w)] + u[row + wrap(x + 1, l.w)] + u[size_t(wrap(y - 1, l.h)) * l.w + x] +
         u[size_t(wrap(y + 1, l.h)) * l.w + x];
}

// Chan 2018 §4.2: each texel's height from its neighbours' heights and the height differences across the edges
// (folded into f), over-relaxed by omega. Red-black order when both sizes are even (every neighbour, across the
// wrap too, has the other colour: deterministic in parallel), lexicographic otherwise. Returns the largest change.
double relax(Level& l, int sweeps, double omega) {
  double largest = 0;
  const bool red_black = l.w % 2 == 0 && l.h % 2 == 0 && l.w >= 2 && l.h >= 2;
  for (int s = 0; s < sweeps; ++s) {
    largest = 0;
    if (red_black) {
      for (int colour = 0; colour < 2; ++colour) {
        std::vector<double> row_max(size_t(l.h), 0.0);
        tbb::parallel_for(0, l.h, [&](int y) {
          double m = 0;
          for (int x = (y + colour) & 1; x < l.w; x += 2) {
            const size_t i = size_t(y) * l.w + x;
            const double target = (neighbour_sum(l, x, y) + l.f[i]) * 0.25;
            const double d = omega * (target - l.u[i]);
            l.u[i] += d;
            m = std::max(m, std::abs(d));
          }
          row_max[size_t(y)] = m;
        });
        for (double m : row_max) largest = std::max(largest, m);
      }
    } else {
      for (int y = 0; y < l.h; ++y)
        for (int x = 0; x < l.w; ++x) {
          const size_t i = size_t(y) * l.w + x;
          const double d = omega * ((neighbour_sum(l, x, y) + l.f[i]) * 0.25 - l.u[i]);
          l.u[i] += d;
          largest = std::max(largest, std::abs(d));
        }
    }
  }
  return largest;
}

// The periodic problem has a solution only when f sums to zero; rounding (and the odd-size restriction, which
// counts a row or column twice) breaks that slightly, so the mean is removed.
void remove_mean(std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  const double m = v.empty() ? 0.0 : s / double(v.size());
  for (double& x : v) x -= m;
}

// f = -div(e) for edge targets ex (h[x+1] - h[x]) and ey (h[y+1] - h[y]), both in level-0 texel widths.
void rhs_from_edges(Level& l, const std::vector<double>& ex, const std::vector<double>& ey) {
  l.f.assign(l.size(), 0.0);
  for (int y = 0; y < l.h; ++y)
    for (int x = 0; x < l.w; ++x) {
      const size_t i = size_t(y) * l.w + x;
      l.f[i] = -ex[i] + ex[size_t(y) * l.w + wrap(x - 1, l.w)] - ey[i] + ey[size_t(wrap(y - 1, l.h)) * l.w + x];
    }
  remove_mean(l.f);
}

// Edge targets of a slope field: the trapezoid rule across each edge, times the level's texel size (sx, sy level-0
// texels), so that every level's heights are in level-0 texel widths.
void edges_from_slopes(const SlopeField& g, double sx, double sy, std::vector<double>& ex, std::vector<double>& ey) {
  const int w = g.width, h = g.height;
  ex.assign(size_t(w) * h, 0.0);
  ey.assign(size_t(w) * h, 0.0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      ex[i] = sx * 0.5 * (double(g.gx[i]) + g.gx[size_t(y) * w + wrap(x + 1, w)]);
      ey[i] = sy * 0.5 * (double(g.gy[i]) + g.gy[size_t(wrap(y + 1, h)) * w + x]);
    }
}

// The next mip of a slope field: 2 x 2 box averages (an odd size wraps its last column or row onto the first).
SlopeField downsample(const SlopeField& g) {
  SlopeField c;
  c.width = std::max(1, (g.width + 1) / 2);
  c.height = std::max(1, (g.height + 1) / 2);
  c.gx.assign(size_t(c.width) * c.height, 0.0f);
  c.gy.assign(c.gx.size(), 0.0f);
  for (int y = 0; y < c.height; ++y)
    for (int x = 0; x < c.width; ++x) {
      double sx = 0, sy = 0;
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
          const size_t i =
              size_t(wrap(2 * y + dy, g.height) % g.height) * g.width + wrap(2 * x + dx, g.width) % g.width;
          sx += g.gx[i];
          sy += g.gy[i];
        }
      c.gx[size_t(y) * c.width + x] = float(sx * 0.25);
      c.gy[size_t(y) * c.width + x] = float(sy * 0.25);
    }
  return c;
}

// Bilinear, wrapping: the value of the coarse grid c at the centres of a w x h grid covering the same tile.
std::vector<double> upsample(const std::vector<double>& c, int cw, int ch, int w, int h) {
  std::vector<double> out(size_t(w) * h);
  for (int y = 0; y < h; ++y) {
    const double fy = (y + 0.5) * double(ch) / h - 0.5;
    const int y0 = int(std::floor(fy));
    const double ty = fy - y0;
    const int ya = wrap(y0, ch), yb = wrap(y0 + 1, ch);
    for (int x = 0; x < w; ++x) {
      const double fx = (x + 0.5) * double(cw) / w - 0.5;
      const int x0 = int(std::floor(fx));
      const double tx = fx - x0;
      const int xa = wrap(x0, cw), xb = wrap(x0 + 1, cw);
      const double top = (1 - tx) * c[size_t(ya) * cw + xa] + tx * c[size_t(ya) * cw + xb];
      const double bottom = (1 - tx) * c[size_t(yb) * cw + xa] + tx * c[size_t(yb) * cw + xb];
      out[size_t(y) * w + x] = (1 - ty) * top + ty * bottom;
    }
  }
  return out;
}

// The coarse-grid right-hand side of a correction: the sum of the fine residuals of each 2 x 2 block (the
// unscaled coarse Laplacian has four times the fine one's texel area).
std::vector<double> restrict_residual(const Level& fine, int cw, int ch) {
  std::vector<double> r(fine.size());
  for (int y = 0; y < fine.h; ++y)
    for (int x = 0; x < fine.w; ++x) {
      const size_t i = size_t(y) * fine.w + x;
      r[i] = fine.f[i] - (4.0 * fine.u[i] - neighbour_sum(fine, x, y));
    }
  std::vector<double> c(size_t(cw) * ch, 0.0);
  for (int y = 0; y < ch; ++y)
    for (int x = 0; x < cw; ++x) {
      double s = 0;
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx)
          s += r[size_t(wrap(2 * y + dy, fine.h) % fine.h) * fine.w + wrap(2 * x + dx, fine.w) % fine.w];
      c[size_t(y) * cw + x] = s;
    }
  remove_mean(c);
  return c;
}

// One V-cycle of the correction scheme on levels[k..]: smooth, restrict the residual, correct, smooth.
void vcycle(std::vector<Level>& levels, size_t k, const HeightFromNormalsOptions& o) {
  Level& l = levels[k];
  if (k + 1 == levels.size()) {
    for (int s = 0; s < o.coarsest_sweeps; s += 16)
      if (relax(l, 16, o.omega) < o.tolerance) break;
    return;
  }
  constexpr int kSmooth = 3;
  relax(l, kSmooth, 1.0);
  Level& c = levels[k + 1];
  c.f = restrict_residual(l, c.w, c.h);
  c.u.assign(c.size(), 0.0);
  vcycle(levels, k + 1, o);
  const std::vector<double> e = upsample(c.u, c.w, c.h, l.w, l.h);
  for (size_t i = 0; i < l.size(); ++i) l.u[i] += e[i];
  relax(l, kSmooth, 1.0);
}

}  // namespace

SlopeField normal_slopes(const float* texels, int width, int height, int channels, bool flip_y, float min_nz) {
  SlopeField g;
  g.width = width;
  g.height = height;
  const size_t n = size_t(width) * size_t(height);
  g.gx.resize(n);
  g.gy.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const float* c = texels + i * size_t(channels);
    const float nx = 2.0f * c[0] - 1.0f;
    float ny = 2.0f * c[1] - 1.0f;
    if (flip_y) ny = -ny;
    const float nz = std::max(2.0f * c[2] - 1.0f, min_nz);
    // The surface z = h(u, v) has the normal (-dh/du, -dh/dv, 1); +v is up the image, y (rows) down it.
    g.gx[i] = -nx / nz;
    g.gy[i] = ny / nz;
  }
  return g;
}

HeightField height_from_slopes(const SlopeField& g, const HeightFromNormalsOptions& o) {
  // The mip chain of the slopes (Chan 2018 Algorithm 5), down to coarsest_size.
  std::vector<SlopeField> mips{g};
  while (std::min(mips.back().width, mips.back().height) > std::max(2, o.coarsest_size))
    mips.push_back(downsample(mips.back()));
  std::vector<Level> levels(mips.size());
  for (size_t k = 0; k < mips.size(); ++k) {
    Level& l = levels[k];
    l.w = mips[k].width;
    l.h = mips[k].height;
    std::vector<double> ex, ey;
    edges_from_slopes(mips[k], double(g.width) / l.w, double(g.height) / l.h, ex, ey);
    rhs_from_edges(l, ex, ey);
  }
  // Solve the coarsest mip, then each finer one from the upsampled solution (Chan 2018 Algorithm 5).
  for (size_t k = levels.size(); k-- > 0;) {
    Level& l = levels[k];
    if (k + 1 == levels.size()) {
      l.u.assign(l.size(), 0.0);
      for (int s = 0; s < o.coarsest_sweeps; s += 16)
        if (relax(l, 16, o.omega) < o.tolerance) break;
    } else {
      const Level& c = levels[k + 1];
      l.u = upsample(c.u, c.w, c.h, l.w, l.h);
      relax(l, o.sweeps_per_level, 1.0);
    }
  }
  // Correction cycles on the level-0 problem (see the header's deviations).
  for (int c = 0; c < o.vcycles && levels.size() > 1; ++c) vcycle(levels, 0, o);

  HeightField out;
  out.width = g.width;
  out.height = g.height;
  std::vector<double>& u = levels[0].u;
  remove_mean(u);
  out.h.assign(u.begin(), u.end());
  return out;
}

double slope_residual(const SlopeField& g, const HeightField& hf) {
  std::vector<double> ex, ey;
  edges_from_slopes(g, 1.0, 1.0, ex, ey);
  const int w = g.width, h = g.height;
  double misfit = 0, total = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      const double dx = double(hf.h[size_t(y) * w + wrap(x + 1, w)]) - hf.h[i];
      const double dy = double(hf.h[size_t(wrap(y + 1, h)) * w + x]) - hf.h[i];
      misfit += (dx - ex[i]) * (dx - ex[i]) + (dy - ey[i]) * (dy - ey[i]);
      total += ex[i] * ex[i] + ey[i] * ey[i];
    }
  return total > 0 ? std::sqrt(misfit / total) : 0.0;
}

std::vector<float> normals_from_height(const HeightField& hf, float height_scale) {
  const int w = hf.width, h = hf.height;
  std::vector<float> rgb(size_t(w) * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double dhdx =
          0.5 * height_scale * (double(hf.h[size_t(y) * w + wrap(x + 1, w)]) - hf.h[size_t(y) * w + wrap(x - 1, w)]);
      const double dhdy =
          0.5 * height_scale * (double(hf.h[size_t(wrap(y + 1, h)) * w + x]) - hf.h[size_t(wrap(y - 1, h)) * w + x]);
      // Inverse of normal_slopes: n ∝ (-dh/dx, +dh/dy_rows, 1) in the map's (u, v up, z) frame.
      const double inv = 1.0 / std::sqrt(dhdx * dhdx + dhdy * dhdy + 1.0);
      float* c = &rgb[(size_t(y) * w + x) * 3];
      c[0] = float(0.5 * (-dhdx * inv + 1.0));
      c[1] = float(0.5 * (dhdy * inv + 1.0));
      c[2] = float(0.5 * (inv + 1.0));
    }
  return rgb;
}

}  // namespace kozu
