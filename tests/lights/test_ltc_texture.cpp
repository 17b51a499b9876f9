// The prefiltered light texture of Heitz et al. 2016 §5.3–5.4 (lights/ltc_texture.h):
//  - every level is the Gaussian clamped to the texture and renormalized, against a brute-force sum in double over
//    all texels, inside the texture, in its margin and (clamped) beyond;
//  - a constant texture stays that constant at every level and every point;
//  - the fetch's coordinates and width are those of the orthogonal projection in the cosine configuration: a
//    square facing the shading point gives its centre and σ = sqrt(r² / 2A), and transforming the whole
//    configuration by M gives the same fetch for the LTC of M as the untransformed one for the cosine.
#include "core/ltc.h"
#include "lights/ltc_texture.h"

#include "core/rng.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace kozu {
namespace {

// Three numbers drawn in order (an argument list would leave the order to the compiler).
Vec3 next_vec3(Pcg32& rng) {
  const float x = rng.next_float(), y = rng.next_float();
  return Vec3(x, y, rng.next_float());
}

std::vector<Rgb> random_texels(int n, uint64_t seed) {
  Pcg32 rng(seed);
  std::vector<Rgb> t(size_t(n) * size_t(n));
  for (Rgb& v : t) {
    const float r = rng.next_float(), g = rng.next_float(), b = rng.next_float();
    v = Rgb(r, g, b) * 4.0f;
  }
  return t;
}

// Σ G(x − y) L(y) / Σ G(x − y) over all texels y, in double, without truncation (values relative to the nearest
// texel's weight, as no double can hold e^-(d²/2σ²) far outside).
Vec3d brute_force_level(const std::vector<Rgb>& t, int n, const Vec2& x, double sigma) {
  double d_min2 = kInfinity;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double dx = x.x - (i + 0.5) / n, dy = x.y - (j + 0.5) / n;
      d_min2 = std::min(d_min2, dx * dx + dy * dy);
    }
  Vec3d sum(0.0);
  double w_sum = 0.0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double dx = x.x - (i + 0.5) / n, dy = x.y - (j + 0.5) / n;
      const double w = std::exp(-(dx * dx + dy * dy - d_min2) / (2.0 * sigma * sigma));
      const Rgb& v = t[size_t(j) * size_t(n) + size_t(i)];
      sum += w * Vec3d(v.r, v.g, v.b);
      w_sum += w;
    }
  return sum / w_sum;
}

TEST(LtcTexture, LevelsAreTheClampedRenormalizedGaussian) {
  constexpr int n = 16;
  const std::vector<Rgb> texels = random_texels(n, 11);
  const LtcTexture tex(texels, n);
  ASSERT_GE(tex.levels(), 6);
  double worst = 0.0;
  for (int k = 1; k < tex.levels(); ++k) {
    const float sigma = tex.level_sigma(k);
    EXPECT_FLOAT_EQ(sigma, std::ldexp(1.0f, k) / n);
    // The level's nodes (spacing σ/2 from -margin), where the lookup returns the stored value itself.
    const float spacing = 0.5f * sigma;
    const int count = int(std::ceil((1.0f + 2.0f * LtcTexture::kMargin) / spacing)) + 1;
    for (int j = 0; j < count; j += std::max(1, count / 7))
      for (int i = 0; i < count; i += std::max(1, count / 9)) {
        const Vec2 x(-LtcTexture::kMargin + float(i) * spacing, -LtcTexture::kMargin + float(j) * spacing);
        const Rgb got = tex.lookup(x, sigma);
        const Vec3d want = brute_force_level(texels, n, x, sigma);
        for (int c = 0; c < 3; ++c) {
          const double err = std::abs(got[c] - want[c]);
          worst = std::max(worst, err);
          EXPECT_LT(err, 1e-4) << "level " << k << " at (" << x.x << ", " << x.y << ") channel " << c;
        }
      }
    // Beyond the margin the coordinates clamp to its edge.
    const Vec2 edge(-LtcTexture::kMargin, 1.0f + LtcTexture::kMargin);
    const Rgb far = tex.lookup(Vec2(-3.0f, 7.0f), sigma), at_edge = tex.lookup(edge, sigma);
    for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(far[c], at_edge[c]);
  }
  std::printf("worst absolute error of the levels (texels in [0, 4]): %.2e\n", worst);
}

TEST(LtcTexture, LevelZeroIsTheTextureClampedToItsEdge) {
  constexpr int n = 8;
  const std::vector<Rgb> texels = random_texels(n, 5);
  const LtcTexture tex(texels, n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const Rgb got = tex.lookup(Vec2((i + 0.5f) / n, (j + 0.5f) / n), 0.0f);
      for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(got[c], texels[size_t(j) * n + size_t(i)][c]);
    }
  const Rgb corner = tex.lookup(Vec2(-2.0f, 5.0f), 0.0f);  // texel (0, n − 1)
  for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(corner[c], texels[size_t(n - 1) * n][c]);
}

TEST(LtcTexture, ConstantTextureStaysConstant) {
  constexpr int n = 32;
  const Rgb value(2.5f, 0.75f, 1.0f);
  const std::vector<Rgb> texels(size_t(n) * n, value);
  const LtcTexture tex(texels, n);
  Pcg32 rng(3);
  for (int i = 0; i < 500; ++i) {
    const float a = rng.next_float() * 6.0f - 3.0f;
    const float b = rng.next_float() * 6.0f - 3.0f;
    const float mantissa = rng.next_float();
    const float sigma = std::ldexp(mantissa, -int(rng.next_float() * 12.0f)) * 8.0f;
    const Rgb got = tex.lookup(Vec2(a, b), sigma);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], value[c], 1e-5f * value[c]) << a << " " << b << " " << sigma;
  }
}

TEST(LtcTexture, FetchIsTheOrthogonalProjectionInTheCosineConfiguration) {
  // A 2 × 2 square facing the shading point at distance r, centred above it: the cosine's fetch is the centre
  // with σ = sqrt(r² / (2 · 4)).
  for (const float r : {0.25f, 1.0f, 7.0f}) {
    Vec2 ab;
    const float sigma = LtcTexture::fetch_sigma(Ltc(), Vec3(-1.0f, -1.0f, r), Vec3(2, 0, 0), Vec3(0, 2, 0), &ab);
    EXPECT_NEAR(ab.x, 0.5f, 1e-6f);
    EXPECT_NEAR(ab.y, 0.5f, 1e-6f);
    EXPECT_NEAR(sigma, std::sqrt(r * r / 8.0f), 1e-6f * r);
  }
  // Off-centre and tilted: the foot of the perpendicular from the origin, in the square's (a, b).
  {
    const Vec3 o(0.3f, -0.2f, 1.5f), e1(1.0f, 0.0f, 0.5f), e2(0.0f, 2.0f, 0.0f);
    Vec2 ab;
    const float sigma = LtcTexture::fetch_sigma(Ltc(), o, e1, e2, &ab);
    const Vec3 q = o + ab.x * e1 + ab.y * e2;
    EXPECT_NEAR(glm::dot(q, e1), 0.0f, 1e-5f);  // q − 0 is normal to the plane
    EXPECT_NEAR(glm::dot(q, e2), 0.0f, 1e-5f);
    const float area = glm::length(glm::cross(e1, e2));
    EXPECT_NEAR(sigma, std::sqrt(glm::dot(q, q) / (2.0f * area)), 1e-5f);
  }
  // Transforming the configuration by M and fetching with the LTC of M gives the cosine's fetch.
  Pcg32 rng(9);
  for (int t = 0; t < 50; ++t) {
    Mat3 m(1.0f);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) m[i][j] += 0.8f * (rng.next_float() - 0.5f);
    if (std::abs(glm::determinant(m)) < 0.2f) continue;
    const Vec3 u0 = next_vec3(rng), u1 = next_vec3(rng), u2 = next_vec3(rng);
    const Vec3 o(u0.x - 0.5f, u0.y - 0.5f, 0.5f + u0.z);
    const Vec3 e1(0.5f + u1.x, 0.2f * u1.y, 0.0f);
    const Vec3 e2(0.1f * u2.x, 0.5f + u2.y, 0.3f * u2.z);
    Vec2 ab_cos, ab_m;
    const float s_cos = LtcTexture::fetch_sigma(Ltc(), o, e1, e2, &ab_cos);
    const float s_m = LtcTexture::fetch_sigma(Ltc(m), m * o, m * e1, m * e2, &ab_m);
    EXPECT_NEAR(ab_m.x, ab_cos.x, 1e-4f);
    EXPECT_NEAR(ab_m.y, ab_cos.y, 1e-4f);
    EXPECT_NEAR(s_m, s_cos, 1e-4f * s_cos);
  }
}

}  // namespace
}  // namespace kozu
