// The SGGX microflake distribution (see sggx.h for the equation map, parameters and deviations).
#include "media/sggx.h"

#include "core/frame.h"
#include "core/warp.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace kozu {
namespace {

constexpr double kPiD = std::numbers::pi;

// S in double precision (see the header: thin distributions need it).
struct SymD {
  double xx, yy, zz, xy, xz, yz;
  explicit SymD(const Sggx& s) : xx(s.xx), yy(s.yy), zz(s.zz), xy(s.xy), xz(s.xz), yz(s.yz) {}
  Vec3d mul(const Vec3d& w) const {
    return Vec3d(xx * w.x + xy * w.y + xz * w.z, xy * w.x + yy * w.y + yz * w.z, xz * w.x + yz * w.y + zz * w.z);
  }
  double quadratic(const Vec3d& w) const {
    return xx * w.x * w.x + yy * w.y * w.y + zz * w.z * w.z + 2.0 * (xy * w.x * w.y + xz * w.x * w.z + yz * w.y * w.z);
  }
  double det() const { return xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz); }
};

Vec3d to_d(const Vec3& v) { return Vec3d(v.x, v.y, v.z); }

// Algorithm 1, steps 2–4, for one ωi: the world-space images ck, cj, ci of the vectors M_k, M_j, M_i
// (M in the (ωk, ωj, ωi) basis, rotated back), so that a visible normal is normalize(u ck + v cj + w ci).
struct VisibleNormalMap {
  Vec3d ck{0.0}, cj{0.0}, ci{0.0};
  bool valid = false;

  VisibleNormalMap(const Sggx& S, const Vec3& wi_f) {
    const SymD s(S);
    const Vec3d wi = glm::normalize(to_d(wi_f));
    Vec3d wk, wj;
    orthonormal_basis(wi, wk, wj);  // step 2
    // Step 3: S in the basis (ωk, ωj, ωi).
    const Vec3d s_wk = s.mul(wk), s_wj = s.mul(wj), s_wi = s.mul(wi);
    const double S_kk = glm::dot(wk, s_wk), S_jj = glm::dot(wj, s_wj), S_ii = glm::dot(wi, s_wi);
    const double S_kj = glm::dot(wk, s_wj), S_ki = glm::dot(wk, s_wi), S_ji = glm::dot(wj, s_wi);
    // Step 4. |S^kji| = |S| (a rotation); the explicit form keeps it consistent with the projected entries.
    const double det_kji = S_kk * S_jj * S_ii - S_kj * S_kj * S_ii - S_ki * S_ki * S_jj - S_ji * S_ji * S_kk +
                           2.0 * S_kj * S_ki * S_ji;
    const double minor = S_jj * S_ii - S_ji * S_ji;
    if (!(S_ii > 0.0) || !(minor > 0.0) || !(det_kji > 0.0)) return;
    const double sqrt_minor = std::sqrt(minor);
    const double inv_sqrt_Sii = 1.0 / std::sqrt(S_ii);
    const double mk_k = std::sqrt(det_kji / minor);                         // M_k = (mk_k, 0, 0)
    const double mj_k = -inv_sqrt_Sii * (S_ki * S_ji - S_kj * S_ii) / sqrt_minor;  // M_j = (mj_k, mj_j, 0)
    const double mj_j = inv_sqrt_Sii * sqrt_minor;
    // M_i = (S_ki, S_ji, S_ii) / sqrt(S_ii)
    ck = mk_k * wk;
    cj = mj_k * wk + mj_j * wj;
    ci = inv_sqrt_Sii * (S_ki * wk + S_ji * wj + S_ii * wi);
    valid = true;
  }

  // Step 6: the normal for a point (u, v, sqrt(1 − u² − v²)) of the visible hemisphere.
  Vec3 normal(double u, double v) const {
    const double w = std::sqrt(std::max(0.0, 1.0 - u * u - v * v));
    const Vec3d m = u * ck + v * cj + w * ci;
    return Vec3(glm::normalize(m));
  }

  // Steps 5 and 6: (u, v) uniform on the unit disk by the concentric map (see the header's deviations).
  Vec3 sample(const Vec2& u) const {
    const Vec2 p = warp::square_to_disk_concentric(u);
    return normal(p.x, p.y);
  }
};

// The MIS proxy's fixed rule on the visible disk: U1 at the 2-point Gauss–Legendre nodes of [0, 1], four
// azimuths per ring, the second ring turned by π/4. Equal weights 1/8.
struct DiskRule {
  std::array<Vec2, 8> p{};
  DiskRule() {
    const double u1[2] = {0.5 - 0.5 / std::sqrt(3.0), 0.5 + 0.5 / std::sqrt(3.0)};
    for (int ring = 0; ring < 2; ++ring)
      for (int k = 0; k < 4; ++k) {
        const double r = std::sqrt(u1[ring]);
        const double phi = 2.0 * kPiD * (k + 0.5 * ring) / 4.0;
        p[static_cast<size_t>(4 * ring + k)] = Vec2(static_cast<float>(r * std::cos(phi)), static_cast<float>(r * std::sin(phi)));
      }
  }
};
const DiskRule kDiskRule;
constexpr float kProxyUniform = 1.0f / 16.0f;

// Eigenvalues of a symmetric 3x3 matrix in closed form (Smith 1961, trigonometric), decreasing.
std::array<double, 3> eigenvalues(const std::array<std::array<double, 3>, 3>& a) {
  const double p1 = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
  const double q = (a[0][0] + a[1][1] + a[2][2]) / 3.0;
  const double p2 = sqr(a[0][0] - q) + sqr(a[1][1] - q) + sqr(a[2][2] - q) + 2.0 * p1;
  if (p2 <= 0.0) return {q, q, q};
  const double p = std::sqrt(p2 / 6.0);
  const double b00 = (a[0][0] - q) / p, b11 = (a[1][1] - q) / p, b22 = (a[2][2] - q) / p;
  const double b01 = a[0][1] / p, b02 = a[0][2] / p, b12 = a[1][2] / p;
  const double det_b = b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02) + b02 * (b01 * b12 - b11 * b02);
  const double r = std::clamp(0.5 * det_b, -1.0, 1.0);
  const double phi = std::acos(r) / 3.0;
  const double l1 = q + 2.0 * p * std::cos(phi);
  const double l3 = q + 2.0 * p * std::cos(phi + 2.0 * kPiD / 3.0);
  return {l1, 3.0 * q - l1 - l3, l3};
}

std::array<std::array<double, 3>, 3> to_matrix(const Sggx& S) {
  return {{{S.xx, S.xy, S.xz}, {S.xy, S.yy, S.yz}, {S.xz, S.yz, S.zz}}};
}

Sggx from_basis_d(const std::array<Vec3d, 3>& w, const std::array<double, 3>& sigma2) {
  double m[3][3] = {};
  for (int k = 0; k < 3; ++k)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) m[a][b] += sigma2[static_cast<size_t>(k)] * w[static_cast<size_t>(k)][a] *
                                                w[static_cast<size_t>(k)][b];  // eq. (9)
  return {static_cast<float>(m[0][0]), static_cast<float>(m[1][1]), static_cast<float>(m[2][2]),
          static_cast<float>(m[0][1]), static_cast<float>(m[0][2]), static_cast<float>(m[1][2])};
}

}  // namespace

namespace sggx {

// ---- construction --------------------------------------------------------------------------------------

Sggx from_basis(const Vec3& w1, const Vec3& w2, const Vec3& w3, float sigma1, float sigma2, float sigma3) {
  return from_basis_d({to_d(w1), to_d(w2), to_d(w3)}, {double(sigma1) * sigma1, double(sigma2) * sigma2,
                                                        double(sigma3) * sigma3});  // eq. (9)
}

Sggx rotated(const Sggx& S, const Mat3& R) {
  const Mat3 m(S.xx, S.xy, S.xz, S.xy, S.yy, S.yz, S.xz, S.yz, S.zz);  // symmetric: layout does not matter
  const Mat3 r = R * m * glm::transpose(R);
  return {r[0][0], r[1][1], r[2][2], r[0][1], r[0][2], r[1][2]};
}

Sggx surface(const Vec3& normal, float roughness) {
  const Vec3d n = glm::normalize(to_d(normal));
  const double s2 = sqr(static_cast<double>(std::max(roughness, kMinRoughness)));  // eq. (13)
  const double x = n.x, y = n.y, z = n.z;
  // eq. (14): n nᵀ + σ² (I − n nᵀ)
  return {static_cast<float>(x * x + s2 * (y * y + z * z)), static_cast<float>(y * y + s2 * (x * x + z * z)),
          static_cast<float>(z * z + s2 * (x * x + y * y)), static_cast<float>(x * y - s2 * x * y),
          static_cast<float>(x * z - s2 * x * z),           static_cast<float>(y * z - s2 * y * z)};
}

Sggx fiber(const Vec3& tangent, float roughness) {
  const Vec3d t = glm::normalize(to_d(tangent));
  const double s2 = sqr(static_cast<double>(std::max(roughness, kMinRoughness)));  // eq. (15)
  const double x = t.x, y = t.y, z = t.z;
  // eq. (16): σ² t tᵀ + (I − t tᵀ)
  return {static_cast<float>(s2 * x * x + (y * y + z * z)), static_cast<float>(s2 * y * y + (x * x + z * z)),
          static_cast<float>(s2 * z * z + (x * x + y * y)), static_cast<float>(s2 * x * y - x * y),
          static_cast<float>(s2 * x * z - x * z),           static_cast<float>(s2 * y * z - y * z)};
}

// ---- evaluation ----------------------------------------------------------------------------------------

float projected_area(const Sggx& S, const Vec3& w) {
  return static_cast<float>(std::sqrt(std::max(SymD(S).quadratic(to_d(w)), 0.0)));  // eq. (11)
}

float max_projected_area(const Sggx& S) {
  return static_cast<float>(std::sqrt(std::max(eigenvalues(to_matrix(S))[0], 0.0)));
}

float D(const Sggx& S, const Vec3& wm_f) {
  // ωmᵀ S⁻¹ ωm = ωmᵀ adj(S) ωm / |S|, so eq. (12) is |S|^{3/2} / (π (ωmᵀ adj(S) ωm)²).
  const SymD s(S);
  const Vec3d w = to_d(wm_f);
  const double a00 = s.yy * s.zz - s.yz * s.yz, a11 = s.xx * s.zz - s.xz * s.xz, a22 = s.xx * s.yy - s.xy * s.xy;
  const double a01 = s.xz * s.yz - s.xy * s.zz, a02 = s.xy * s.yz - s.xz * s.yy, a12 = s.xy * s.xz - s.xx * s.yz;
  const double det = s.xx * a00 + s.xy * a01 + s.xz * a02;
  const double q = a00 * w.x * w.x + a11 * w.y * w.y + a22 * w.z * w.z +
                   2.0 * (a01 * w.x * w.y + a02 * w.x * w.z + a12 * w.y * w.z);
  if (!(det > 0.0) || !(q > 0.0)) return 0.0f;
  return static_cast<float>(det * std::sqrt(det) / (kPiD * q * q));  // eq. (12)
}

float D_visible(const Sggx& S, const Vec3& wi, const Vec3& wm) {
  const float cos_im = glm::dot(wi, wm);
  if (cos_im <= 0.0f) return 0.0f;
  const float sigma = projected_area(S, wi);
  return sigma > 0.0f ? cos_im * D(S, wm) / sigma : 0.0f;  // eq. (21)
}

Vec3 sample_visible(const Sggx& S, const Vec3& wi, const Vec2& u) {
  const VisibleNormalMap map(S, wi);
  return map.valid ? map.sample(u) : wi;
}

// ---- linear algebra ------------------------------------------------------------------------------------

SymmetricEigen eigen(const std::array<std::array<double, 3>, 3>& m) {
  double a[3][3], v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) a[i][j] = 0.5 * (m[i][j] + m[j][i]);
  // Cyclic Jacobi: each rotation zeroes one off-diagonal entry; quadratic convergence, ~4-6 sweeps.
  for (int sweep = 0; sweep < 64; ++sweep) {
    const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    const double diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
    if (off == 0.0 || off <= 1e-36 * diag) break;
    for (const auto& [p, q] : {std::pair{0, 1}, std::pair{0, 2}, std::pair{1, 2}}) {
      if (a[p][q] == 0.0) continue;
      const double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
      const double t = std::abs(theta) > 1e150 ? 0.5 / theta
                                               : std::copysign(1.0, theta) / (std::abs(theta) + std::sqrt(theta * theta + 1.0));
      const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
      for (int k = 0; k < 3; ++k) {  // A J
        const double akp = a[k][p], akq = a[k][q];
        a[k][p] = c * akp - s * akq;
        a[k][q] = s * akp + c * akq;
      }
      for (int k = 0; k < 3; ++k) {  // Jᵀ (A J)
        const double apk = a[p][k], aqk = a[q][k];
        a[p][k] = c * apk - s * aqk;
        a[q][k] = s * apk + c * aqk;
      }
      a[p][q] = a[q][p] = 0.0;
      for (int k = 0; k < 3; ++k) {  // V J
        const double vkp = v[k][p], vkq = v[k][q];
        v[k][p] = c * vkp - s * vkq;
        v[k][q] = s * vkp + c * vkq;
      }
    }
  }
  std::array<int, 3> order = {0, 1, 2};
  std::sort(order.begin(), order.end(), [&](int i, int j) { return a[i][i] > a[j][j]; });
  SymmetricEigen e;
  for (size_t k = 0; k < 3; ++k) {
    const int c = order[k];
    e.values[k] = a[c][c];
    e.vectors[k] = glm::normalize(Vec3d(v[0][c], v[1][c], v[2][c]));
  }
  if (glm::dot(glm::cross(e.vectors[0], e.vectors[1]), e.vectors[2]) < 0.0) e.vectors[2] = -e.vectors[2];
  return e;
}

SymmetricEigen eigen(const Sggx& S) { return eigen(to_matrix(S)); }

bool is_spd(const Sggx& S) {
  const SymD s(S);
  if (!std::isfinite(s.xx) || !std::isfinite(s.yy) || !std::isfinite(s.zz) || !std::isfinite(s.xy) ||
      !std::isfinite(s.xz) || !std::isfinite(s.yz))
    return false;
  return s.xx > 0.0 && s.xx * s.yy - s.xy * s.xy > 0.0 && s.det() > 0.0;
}

Sggx lerp(const Sggx& a, const Sggx& b, float t) { return a * (1.0f - t) + b * t; }

// ---- parameter estimation ------------------------------------------------------------------------------

namespace {

// ∫ f(ω) dω over θ in [0, theta_max] (all directions about the pole e3 of (e1, e2, e3)), with `cells` cells
// in θ of width π/resolution... by 4x4 Gauss–Legendre per cell; f receives the world direction.
template <typename F>
void integrate_sphere(const Vec3d& e1, const Vec3d& e2, const Vec3d& e3, int theta_cells, double theta_max,
                      int phi_cells, const F& f) {
  static constexpr double kX[4] = {0.0694318442029737, 0.3300094782075719, 0.6699905217924281, 0.9305681557970263};
  static constexpr double kW[4] = {0.1739274225687269, 0.3260725774312731, 0.3260725774312731, 0.1739274225687269};
  const double dtheta = theta_max / theta_cells, dphi = 2.0 * kPiD / phi_cells;
  std::vector<double> cphi(static_cast<size_t>(phi_cells) * 4), sphi(cphi.size());
  for (int j = 0; j < phi_cells; ++j)
    for (int b = 0; b < 4; ++b) {
      const double phi = (j + kX[b]) * dphi;
      cphi[static_cast<size_t>(4 * j + b)] = std::cos(phi);
      sphi[static_cast<size_t>(4 * j + b)] = std::sin(phi);
    }
  for (int i = 0; i < theta_cells; ++i)
    for (int a = 0; a < 4; ++a) {
      const double theta = (i + kX[a]) * dtheta;
      const double st = std::sin(theta), ct = std::cos(theta);
      const double wa = kW[a] * dtheta * st;
      for (int j = 0; j < phi_cells; ++j)
        for (int b = 0; b < 4; ++b) {
          const size_t node = static_cast<size_t>(4 * j + b);
          const Vec3d w = st * cphi[node] * e1 + st * sphi[node] * e2 + ct * e3;
          f(w, wa * kW[b] * dphi);
        }
    }
}

}  // namespace

Sggx estimate(const std::function<double(const Vec3&)>& D_in, int resolution) {
  resolution = std::max(resolution, 2);
  // Eq. (18): the second moments of the normals (no clamp: a smooth integrand over the whole sphere).
  std::array<std::array<double, 3>, 3> cov{};
  integrate_sphere(Vec3d(1, 0, 0), Vec3d(0, 1, 0), Vec3d(0, 0, 1), resolution, kPiD, 2 * resolution,
                   [&](const Vec3d& w, double weight) {
                     const double d = D_in(Vec3(w)) * weight;
                     for (int a = 0; a < 3; ++a)
                       for (int b = a; b < 3; ++b) cov[a][b] += w[a] * w[b] * d;
                   });
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < a; ++b) cov[a][b] = cov[b][a];
  const SymmetricEigen e = eigen(cov);
  // Eq. (17): σ(ω_k) = ∫⟨ω_k, ωm⟩ D dωm over the hemisphere about ω_k (the clamp is the cells' edge).
  std::array<double, 3> sigma2{};
  const int half = (resolution + 1) / 2;
  for (size_t k = 0; k < 3; ++k) {
    Vec3d e1, e2;
    orthonormal_basis(e.vectors[k], e1, e2);
    double sigma = 0.0;
    integrate_sphere(e1, e2, e.vectors[k], half, 0.5 * kPiD, 2 * resolution, [&](const Vec3d& w, double weight) {
      sigma += glm::dot(w, e.vectors[k]) * D_in(Vec3(w)) * weight;  // eq. (17)
    });
    sigma2[k] = sigma * sigma;
  }
  return from_basis_d(e.vectors, sigma2);  // eq. (9)
}

Sggx estimate_from_normals(std::span<const WeightedNormal> normals) {
  std::array<std::array<double, 3>, 3> cov{};
  double total = 0.0;
  for (const WeightedNormal& wn : normals) {
    const Vec3d n = glm::normalize(to_d(wn.n));
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) cov[a][b] += wn.weight * n[a] * n[b];  // eq. (18)
    total += wn.weight;
  }
  if (!(total > 0.0)) return Sggx{};
  const SymmetricEigen e = eigen(cov);
  std::array<double, 3> sigma2{};
  for (size_t k = 0; k < 3; ++k) {
    double sigma = 0.0;
    for (const WeightedNormal& wn : normals)
      sigma += wn.weight * std::abs(glm::dot(e.vectors[k], glm::normalize(to_d(wn.n))));  // eq. (17)
    sigma2[k] = sqr(sigma / total);
  }
  return from_basis_d(e.vectors, sigma2);  // eq. (9)
}

// ---- compact storage -----------------------------------------------------------------------------------

SggxCompact compress(const Sggx& S, float sigma_scale) {
  const double d[3] = {std::max<double>(S.xx, 0.0), std::max<double>(S.yy, 0.0), std::max<double>(S.zz, 0.0)};
  const double off[3] = {S.xy, S.xz, S.yz};
  constexpr int kPair[3][2] = {{0, 1}, {0, 2}, {1, 2}};
  SggxCompact c;
  for (size_t a = 0; a < 3; ++a) {
    const double sigma = std::sqrt(d[a]) / sigma_scale;  // eq. (19)
    c.sigma[a] = static_cast<uint8_t>(std::lround(std::clamp(sigma, 0.0, 1.0) * 255.0));
    const double norm = std::sqrt(d[kPair[a][0]] * d[kPair[a][1]]);
    const double r = norm > 0.0 ? off[a] / norm : 0.0;  // eq. (19)
    c.r[a] = static_cast<int8_t>(std::lround(std::clamp(r, -1.0, 1.0) * 127.0));
  }
  return c;
}

Sggx decompress(const SggxCompact& c, float sigma_scale) {
  double sigma[3], r[3];
  for (size_t a = 0; a < 3; ++a) {
    sigma[a] = c.sigma[a] / 255.0 * sigma_scale;
    r[a] = c.r[a] / 127.0;
  }
  // Guard: the correlation matrix R = [[1, rxy, rxz], [rxy, 1, ryz], [rxz, ryz, 1]] must stay positive definite.
  // λ ≤ 3 (Gershgorin), so det R ≥ 9 δ with R positive definite already gives λ_min ≥ δ.
  const double det_r = 1.0 + 2.0 * r[0] * r[1] * r[2] - r[0] * r[0] - r[1] * r[1] - r[2] * r[2];
  if (!(1.0 - r[0] * r[0] > 0.0 && det_r >= 9.0 * kCompactMinEigen)) {
    const double lmin = eigenvalues({{{1.0, r[0], r[1]}, {r[0], 1.0, r[2]}, {r[1], r[2], 1.0}}})[2];
    if (lmin < kCompactMinEigen) {
      const double k = (1.0 - kCompactMinEigen) / (1.0 - lmin);  // eigenvalues 1 + k μ of I + k (R − I)
      for (double& x : r) x *= k;
    }
  }
  // eq. (20)
  return {static_cast<float>(sigma[0] * sigma[0]), static_cast<float>(sigma[1] * sigma[1]),
          static_cast<float>(sigma[2] * sigma[2]), static_cast<float>(r[0] * sigma[0] * sigma[1]),
          static_cast<float>(r[1] * sigma[0] * sigma[2]), static_cast<float>(r[2] * sigma[1] * sigma[2])};
}

}  // namespace sggx

// ---- phase functions -----------------------------------------------------------------------------------

float SggxSpecularPhase::eval(const Vec3& wo, const Vec3& wi, Pcg32&) const { return pdf(wo, wi); }

float SggxSpecularPhase::pdf(const Vec3& wo, const Vec3& wi) const {
  const Vec3 h = wo + wi;
  const float len2 = glm::dot(h, h);
  if (!(len2 > 1e-12f)) return 0.0f;  // wi = −wo: no microflake reflects straight through
  const float sigma = sggx::projected_area(S_, wo);
  if (!(sigma > 0.0f)) return 0.0f;
  return sggx::D(S_, h / std::sqrt(len2)) / (4.0f * sigma);  // eq. (24)
}

PhaseSample SggxSpecularPhase::sample(const Vec3& wo, const Vec2& u, Pcg32&) const {
  const Vec3 wm = sggx::sample_visible(S_, wo, u);
  PhaseSample s;
  s.wi = glm::normalize(reflect(wo, wm));  // §5.3: mirror wo about the visible normal
  s.pdf = pdf(wo, s.wi);
  s.f = s.pdf;  // the sampling density is f_p itself
  return s;
}

float SggxDiffusePhase::eval(const Vec3& wo, const Vec3& wi, Pcg32& rng) const {
  const VisibleNormalMap map(S_, wo);
  if (!map.valid) return 0.0f;
  float sum = 0.0f;
  for (int j = 0; j < samples_; ++j) {
    const float u1 = rng.next_float();
    const Vec3 wm = map.sample(Vec2(u1, rng.next_float()));
    sum += std::max(glm::dot(wi, wm), 0.0f);  // eq. (26)
  }
  return sum * kInvPi / static_cast<float>(samples_);
}

float SggxDiffusePhase::pdf(const Vec3& wo, const Vec3& wi) const {
  const VisibleNormalMap map(S_, wo);
  if (!map.valid) return kInv4Pi;
  float sum = 0.0f;
  for (const Vec2& p : kDiskRule.p) sum += std::max(glm::dot(wi, map.normal(p.x, p.y)), 0.0f);
  return (1.0f - kProxyUniform) * sum * (kInvPi / 8.0f) + kProxyUniform * kInv4Pi;
}

PhaseSample SggxDiffusePhase::sample(const Vec3& wo, const Vec2& u, Pcg32& rng) const {
  const Vec3 wm = sggx::sample_visible(S_, wo, u);
  const float u1 = rng.next_float();
  const Vec3 local = warp::square_to_cosine_hemisphere(Vec2(u1, rng.next_float()));
  PhaseSample s;
  s.wi = glm::normalize(Frame(wm).to_world(local));  // §5.3: Lambertian reflection off the visible flake
  s.pdf = pdf(wo, s.wi);  // the MIS proxy
  s.f = s.pdf;            // weight 1: eq. (25) is sampled exactly
  return s;
}

}  // namespace kozu
