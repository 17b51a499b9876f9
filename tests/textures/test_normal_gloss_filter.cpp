// Normal and gloss mip filtering (textures/normal_gloss_filter.h, D. Chan, "Material Advances in Call of Duty: WWII",
// SIGGRAPH 2018 course Advances in Real-Time Rendering in Games, §2): the closed forms of the shortened normal's
// length (eqs. (24), (26)) against numerical integration of the GGX NDF, their inverses, Algorithms 1 and 2 on
// normal maps drawn from a GGX distribution of known alpha, flat maps, and the files the tool writes.
#include "core/error.h"
#include "core/rng.h"
#include "io/image_io.h"
#include "textures/normal_gloss_files.h"
#include "textures/normal_gloss_filter.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <vector>

namespace kozu {
namespace {

constexpr double kPi = std::numbers::pi;

// GGX NDF, alpha^2 / (pi (cos^2 (alpha^2 - 1) + 1)^2), with no division by cos (finite at the horizon).
double ggx_d(double cos_theta, double alpha) {
  const double alpha2 = alpha * alpha;
  const double t = cos_theta * cos_theta * (alpha2 - 1.0) + 1.0;
  return alpha2 / (kPi * t * t);
}

// 2 pi int_0^{pi/2} D(theta) cos^k(theta) sin(theta) dtheta by composite Simpson with 200,000 intervals (h = 7.9e-6
// rad, 1/1270 of the narrowest lobe tested, alpha = 0.01): error far below the 1e-9 the tests ask.
double ndf_moment(double alpha, int k) {
  const int n = 200000;
  const double h = 0.5 * kPi / n;
  const auto f = [&](double theta) {
    const double c = std::cos(theta);
    return ggx_d(c, alpha) * std::pow(c, k) * std::sin(theta);
  };
  double sum = f(0.0) + f(0.5 * kPi);
  for (int i = 1; i < n; ++i) sum += (i % 2 ? 4.0 : 2.0) * f(i * h);
  return 2.0 * kPi * sum * h / 3.0;
}

const double kAlphas[] = {0.01, 0.05, 0.1, 0.25, 0.5, 0.75, 0.9, 0.968, 0.97, 0.999, 1.0};

TEST(NormalGlossFilter, ClosedFormsMatchIntegratedGgx) {
  double worst_micro = 0, worst_macro = 0;
  for (double alpha : kAlphas) {
    SCOPED_TRACE(alpha);
    worst_micro = std::max(worst_micro, std::abs(shortened_normal_length_micro(alpha) - 1.0 / ndf_moment(alpha, 0)));
    worst_macro = std::max(worst_macro, std::abs(shortened_normal_length_macro(alpha) - ndf_moment(alpha, 2)));
    EXPECT_NEAR(ndf_moment(alpha, 1), 1.0, 1e-9);  // eq. (11): projected area 1
    // eq. (23) = (24): 1 / int D dw; eq. (25) = (26): int D cos^2 dw.
    EXPECT_NEAR(shortened_normal_length_micro(alpha), 1.0 / ndf_moment(alpha, 0), 1e-9);
    EXPECT_NEAR(shortened_normal_length_macro(alpha), ndf_moment(alpha, 2), 1e-9);
  }
  std::printf("closed forms against integration over alpha in [0.01, 1]: eq. (24) %.2g, eq. (26) %.2g\n", worst_micro,
              worst_macro);
  EXPECT_NEAR(shortened_normal_length_macro(1.0), 2.0 / 3.0, 1e-15);
  EXPECT_NEAR(shortened_normal_length_micro(1.0), 0.5, 1e-15);
  EXPECT_NEAR(shortened_normal_length_macro(0.0), 1.0, 1e-15);
  EXPECT_NEAR(shortened_normal_length_micro(0.0), 1.0, 1e-15);
  // The macro closed form switches to its series below a = 0.25: no jump there (the slope is below 1, so 2e-12 of
  // alpha moves the length by less than 3e-12).
  const double alpha_switch = std::sqrt(1.0 - 0.25 * 0.25);
  EXPECT_NEAR(shortened_normal_length_macro(alpha_switch * (1 + 1e-12)),
              shortened_normal_length_macro(alpha_switch * (1 - 1e-12)), 3e-12);
}

TEST(NormalGlossFilter, GlossAndLengthRoundTrip) {
  for (auto model : {ShortenedNormalModel::Macro, ShortenedNormalModel::Micro}) {
    double previous = 0, worst = 0;
    for (int i = 0; i <= 1000; ++i) {
      const double g = i / 1000.0;
      const double len = gloss_to_normal_length(g, model);
      EXPECT_NEAR(len, shortened_normal_length(wwii_gloss_to_alpha(g), model), 1e-12);
      if (i > 0) {
        EXPECT_GT(len, previous);  // monotone: the inverse is unique
      }
      previous = len;
      EXPECT_NEAR(normal_length_to_gloss(len, model), g, 1e-9) << "g " << g;
      worst = std::max(worst, std::abs(normal_length_to_gloss(len, model) - g));
      EXPECT_NEAR(wwii_alpha_to_gloss(wwii_gloss_to_alpha(g)), g, 1e-12);
    }
    std::printf("%s: g -> L -> g within %.2g over g in [0, 1]\n",
                model == ShortenedNormalModel::Macro ? "macro" : "micro", worst);
    // Lengths beyond the range of eq. (2)'s gloss clamp.
    EXPECT_EQ(normal_length_to_gloss(0.3, model), 0.0);
    EXPECT_EQ(normal_length_to_gloss(1.0, model), 1.0);
  }
  EXPECT_NEAR(wwii_gloss_to_alpha(0.0), 1.0, 1e-15);  // eq. (2): g = 0 is GGX's roughest
}

// The paper's rational fits of the macro table, eqs. (40) and (42), against the closed form they approximate: the
// figures docs/wwii.md gives. Bound: a gloss of 1/255 (one 8-bit step) changes the length by at least 1.2e-4
// (near g = 1), so a fit worth its place is within a few 1e-3.
TEST(NormalGlossFilter, PaperFitsAgainstClosedForm) {
  for (int eq : {40, 42}) {
    double max_err = 0, max_g_err = 0, max_g_err_below = 0, at = 0;
    for (int i = 0; i <= 1000; ++i) {
      const double g = i / 1000.0;
      const double fit = gloss_to_normal_length_fit(g, eq);
      max_err = std::max(max_err, std::abs(fit - gloss_to_normal_length(g, ShortenedNormalModel::Macro)));
      const double g_err = std::abs(normal_length_to_gloss(fit, ShortenedNormalModel::Macro) - g);
      if (g_err > max_g_err) max_g_err = g_err, at = g;
      if (g <= 0.75) max_g_err_below = std::max(max_g_err_below, g_err);
    }
    std::printf(
        "eq. (%d): max |length error| %.3g; its length read back through the exact inverse: max gloss error "
        "%.3g (at g %.3f), %.3g for g <= 0.75\n",
        eq, max_err, max_g_err, at, max_g_err_below);
    EXPECT_LT(max_err, 5e-3) << "eq. " << eq;
  }
  // Eq. (42) pins f(1) to the paper's table value 0.999958 (eq. (41); its printed coefficients give 0.999961), which
  // the closed form reproduces to its 6 digits.
  EXPECT_NEAR(gloss_to_normal_length_fit(1.0, 42), 0.999958, 5e-6);
  EXPECT_NEAR(gloss_to_normal_length(1.0, ShortenedNormalModel::Macro), 0.999958, 1e-6);
  EXPECT_NEAR(gloss_to_normal_length(0.0, ShortenedNormalModel::Macro), 0.66667, 1e-5);  // the f(0) of eq. (41)
}

// A size x size map whose normals are drawn from GGX of roughness alpha by projected (macro-surface) area, the
// pdf D cos of eq. (14): tan^2 theta = alpha^2 u / (1 - u). Encoded with the gloss `gloss` everywhere.
NormalGlossLevel ggx_map(int size, double alpha, float gloss, uint64_t seed) {
  NormalGlossLevel l;
  l.width = l.height = size;
  Pcg32 rng(seed);
  for (int i = 0; i < size * size; ++i) {
    const double u = rng.next_double(), phi = 2 * kPi * rng.next_double();
    const double tan2 = alpha * alpha * u / (1.0 - u);
    const double cos_t = 1.0 / std::sqrt(1.0 + tan2), sin_t = std::sqrt(tan2) * cos_t;
    l.normal.push_back(static_cast<float>(sin_t * std::cos(phi)));
    l.normal.push_back(static_cast<float>(sin_t * std::sin(phi)));
    l.normal.push_back(static_cast<float>(cos_t));
    l.gloss.push_back(gloss);
  }
  return l;
}

double texel_length(const NormalGlossLevel& level, size_t i, ShortenedNormalModel model) {
  return gloss_to_normal_length(level.gloss[i], model);
}

// Algorithm 2 (macro) on a 256 x 256 map drawn from GGX(alpha): a texel of a level k steps down averages n = 4^k
// normals, so its shortened length is L_b L(alpha) (L_b the base gloss's length) up to the mean's noise: the z
// component's standard deviation sqrt((E[z^2] - L^2) / n), E[z^2] = int D cos^3 dw, plus the bias of |mean| from
// the x, y components' variance, (1 - E[z^2]) / (2 n L). Every texel of the 4 x 4, 2 x 2 and 1 x 1 levels (21
// texels) must lie within 4 standard deviations (family-wise false alarm < 2e-3 under the normal approximation),
// widened by what the gloss clamp adds: a 2 x 2 mean shorter than gloss 0's length L(0) = 2/3 (GGX's tail makes a
// few) is stored as gloss 0, its length lifted by L(0) - |mean|, which moves a coarse texel by at most the lifts in
// its footprint times their share of its area (computed here from level 0; no texel of a coarser level may clamp).
// The models differ by more than 20 of the 1 x 1 level's deviations at every alpha, so the check tells them apart.
TEST(NormalGlossFilter, Algorithm2RecoversGgxLength) {
  const float base_gloss = 1.0f;
  const auto macro = ShortenedNormalModel::Macro;
  const double lb = gloss_to_normal_length(base_gloss, macro), l0 = gloss_to_normal_length(0.0, macro);
  for (double alpha : {0.1, 0.25, 0.4}) {
    SCOPED_TRACE(alpha);
    const NormalGlossLevel map = ggx_map(256, alpha, base_gloss, 29);
    const auto levels = filter_normal_gloss(map, macro);
    ASSERT_EQ(levels.size(), 9u);
    // The lifts of level 1's clamped texels, from their raw 2 x 2 means.
    std::vector<double> lift(128 * 128, 0.0);
    int clamped = 0;
    for (int y = 0; y < 128; ++y)
      for (int x = 0; x < 128; ++x) {
        if (levels[1].gloss[size_t(y) * 128 + size_t(x)] != 0.0f) continue;
        double v[3] = {0, 0, 0};
        for (int dy = 0; dy < 2; ++dy)
          for (int dx = 0; dx < 2; ++dx)
            for (int c = 0; c < 3; ++c) v[c] += 0.25 * lb * map.normal[3 * (size_t(2 * y + dy) * 256 + 2 * x + dx) + c];
        lift[size_t(y) * 128 + size_t(x)] = l0 - std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        ++clamped;
      }
    for (size_t k = 2; k < levels.size(); ++k)
      EXPECT_EQ(std::count(levels[k].gloss.begin(), levels[k].gloss.end(), 0.0f), 0) << "level " << k;
    const double len = shortened_normal_length_macro(alpha), ez2 = ndf_moment(alpha, 3);
    const double sigma1 = std::sqrt((ez2 - len * len) / (256.0 * 256.0));
    EXPECT_GT(std::abs(len - shortened_normal_length_micro(alpha)), 20 * sigma1);
    for (size_t k = 6; k <= 8; ++k) {
      const double n = std::pow(4.0, double(k));
      const double sigma = lb * std::sqrt((ez2 - len * len) / n);
      const double expected = lb * (len + (1 - ez2) / (2 * n * len));
      const NormalGlossLevel& l = levels[k];
      const int side = 1 << (k - 1);  // level-1 texels a side of a level-k texel
      for (int y = 0; y < l.height; ++y)
        for (int x = 0; x < l.width; ++x) {
          double bound = 0;
          for (int cy = y * side; cy < (y + 1) * side; ++cy)
            for (int cx = x * side; cx < (x + 1) * side; ++cx) bound += lift[size_t(cy) * 128 + size_t(cx)];
          bound /= double(side * side);
          const size_t i = size_t(y) * size_t(l.width) + size_t(x);
          const double got = texel_length(l, i, macro), band = 4 * sigma + bound;
          EXPECT_NEAR(got, expected, band) << "level " << k << " texel " << i;
          // The gloss itself: the inverse of the closed form at the expected length, within the same band.
          EXPECT_LE(l.gloss[i], normal_length_to_gloss(expected + band, macro) + 1e-6);
          EXPECT_GE(l.gloss[i], normal_length_to_gloss(expected - band, macro) - 1e-6);
          if (k == 8)
            std::printf(
                "alpha %.2f: macro 1 x 1 length %.6f, closed form x L_b %.6f (sigma %.2g; %d 2 x 2 means "
                "clamped, lifting it by %.2g at most), gloss %.4f vs %.4f\n",
                alpha, got, lb * len, sigma, clamped, bound, l.gloss[i], normal_length_to_gloss(lb * len, macro));
        }
    }
  }
}

// Algorithm 1 (micro) on the same maps: the level's length estimates L_b N / sum(1 / z_i), whose deviation, by the
// delta method, is L_b L^2 s / sqrt(n) with s the standard deviation of 1 / z over the map (measured: its true
// variance diverges logarithmically at the horizon, so the sample's is used), within 4 of them.
TEST(NormalGlossFilter, Algorithm1RecoversGgxLength) {
  const float base_gloss = 1.0f;
  const double lb = gloss_to_normal_length(base_gloss, ShortenedNormalModel::Micro);
  for (double alpha : {0.1, 0.3}) {
    SCOPED_TRACE(alpha);
    const NormalGlossLevel map = ggx_map(256, alpha, base_gloss, 31);
    double s1 = 0, s2 = 0;
    for (size_t i = 0; i < map.gloss.size(); ++i) {
      const double w = 1.0 / std::max<double>(map.normal[3 * i + 2], 0.01);
      s1 += w, s2 += w * w;
    }
    const double count = double(map.gloss.size());
    const double s = std::sqrt(s2 / count - (s1 / count) * (s1 / count));
    const auto levels = filter_normal_gloss(map, ShortenedNormalModel::Micro);
    const double len = shortened_normal_length_micro(alpha);
    // Exact recursion: with no texel clamped (to gloss 0 or to n_z >= 0.01), the 1 x 1 level equals the whole map's
    // micro-surface-weighted mean.
    if (alpha == 0.1) {
      EXPECT_EQ(std::count(levels[1].gloss.begin(), levels[1].gloss.end(), 0.0f), 0);
      EXPECT_NEAR(texel_length(levels[8], 0, ShortenedNormalModel::Micro), lb * count / s1, 2e-6);
    }
    for (size_t k = 6; k <= 8; ++k) {
      const double sigma = lb * len * len * s / std::sqrt(std::pow(4.0, double(k)));
      const NormalGlossLevel& l = levels[k];
      for (size_t i = 0; i < l.gloss.size(); ++i)
        EXPECT_NEAR(texel_length(l, i, ShortenedNormalModel::Micro), lb * len, 4 * sigma)
            << "level " << k << " texel " << i;
      if (k == 8)
        std::printf("alpha %.2f: micro 1 x 1 length %.6f, closed form x L_b %.6f (sigma %.2g)\n", alpha,
                    texel_length(l, 0, ShortenedNormalModel::Micro), lb * len, sigma);
    }
  }
}

// A flat map keeps its gloss and its normal at every level, odd sizes included (64 x 48 -> ... 4 x 3 -> 2 x 1).
TEST(NormalGlossFilter, FlatMapKeepsGloss) {
  for (auto model : {ShortenedNormalModel::Macro, ShortenedNormalModel::Micro})
    for (float g : {0.0f, 0.3f, 0.77f, 1.0f}) {
      NormalGlossLevel l;
      l.width = 64, l.height = 48;
      for (int i = 0; i < 64 * 48; ++i) l.normal.insert(l.normal.end(), {0.0f, 0.0f, 1.0f}), l.gloss.push_back(g);
      const auto levels = filter_normal_gloss(l, model);
      ASSERT_EQ(levels.size(), 7u);
      EXPECT_EQ(levels[5].width, 2);
      EXPECT_EQ(levels[5].height, 1);
      for (const NormalGlossLevel& level : levels)
        for (size_t i = 0; i < level.gloss.size(); ++i) {
          EXPECT_NEAR(level.gloss[i], g, 1e-6);
          EXPECT_EQ(level.normal[3 * i + 2], 1.0f);
        }
    }
}

// The direction of a mix of two facets follows the glossier one (its longer shortened normal, Chan 2018 fig. 7).
TEST(NormalGlossFilter, MixedGlossLeansToGlossierNormal) {
  NormalGlossLevel l;
  l.width = 2, l.height = 1;
  const float s = std::sin(0.3f), c = std::cos(0.3f);
  l.normal = {s, 0, c, -s, 0, c};
  l.gloss = {0.9f, 0.2f};
  const auto levels = filter_normal_gloss(l, ShortenedNormalModel::Macro);
  ASSERT_EQ(levels.size(), 2u);
  EXPECT_GT(levels[1].normal[0], 0.0f);
  EXPECT_LT(levels[1].gloss[0], 0.9f);
}

std::filesystem::path temp_dir() {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("kozu_test_normal_gloss_" + std::to_string(static_cast<long>(getpid())));
  std::filesystem::create_directories(dir);
  return dir;
}

// The files: written with explicit mip levels (.exr and .tx), every level read back equals the chain in memory.
TEST(NormalGlossFilter, FilesHoldEveryLevel) {
  const auto dir = temp_dir();
  const NormalGlossLevel map = ggx_map(32, 0.4, 0.8f, 7);
  Image normal, gloss;
  normal.width = gloss.width = 32, normal.height = gloss.height = 32, normal.channels = 3, gloss.channels = 1;
  for (float v : map.normal) normal.data.push_back(0.5f * (v + 1.0f));
  Pcg32 rng(3);
  std::vector<float> g(32 * 32);
  for (float& v : g) v = 0.5f + 0.5f * rng.next_float();
  gloss.data = g;
  write_mip_levels(dir / "n.exr", {normal});
  write_mip_levels(dir / "g.exr", {gloss});
  for (const char* ext : {".exr", ".tx"}) {
    SCOPED_TRACE(ext);
    NormalGlossFilterJob job;
    job.normal_map = dir / "n.exr";
    job.gloss_map = dir / "g.exr";
    job.out_normal = dir / (std::string("on") + ext);
    job.out_gloss = dir / (std::string("og") + ext);
    const NormalGlossFilterSummary summary = filter_normal_gloss_files(job);
    EXPECT_EQ(summary.levels, 6);
    EXPECT_EQ(probe_image(job.out_normal).mip_levels, 6);
    EXPECT_EQ(probe_image(job.out_gloss).mip_levels, 6);
    NormalGlossLevel in;
    in.width = in.height = 32;
    for (float v : normal.data) in.normal.push_back(2.0f * v - 1.0f);
    in.gloss = g;
    const auto levels = filter_normal_gloss(in, ShortenedNormalModel::Macro);
    for (int k = 0; k < 6; ++k) {
      const Image n = read_mip_level(job.out_normal, k), gl = read_mip_level(job.out_gloss, k);
      ASSERT_EQ(n.width, levels[k].width);
      ASSERT_EQ(gl.height, levels[k].height);
      ASSERT_EQ(n.channels, 3);
      ASSERT_EQ(gl.channels, 1);
      for (size_t i = 0; i < levels[k].gloss.size(); ++i) {
        EXPECT_NEAR(gl.data[i], levels[k].gloss[i], 1e-6);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(2.0f * n.data[3 * i + c] - 1.0f, levels[k].normal[3 * i + c], 1e-5);
      }
    }
    EXPECT_THROW(read_mip_level(job.out_gloss, 6), InputError);
  }
  // Bad input: a gloss outside [0, 1] names the gloss file; nothing is written.
  gloss.data[5] = 1.5f;
  write_mip_levels(dir / "bad.exr", {gloss});
  NormalGlossFilterJob job;
  job.normal_map = dir / "n.exr";
  job.gloss_map = dir / "bad.exr";
  job.out_normal = dir / "x.exr";
  job.out_gloss = dir / "y.exr";
  try {
    filter_normal_gloss_files(job);
    ADD_FAILURE() << "accepted a gloss of 1.5";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.exr"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("outside [0, 1]"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "x.exr"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace kozu
