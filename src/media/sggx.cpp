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

// S in double precision, for the eigen-analysis and estimation code (not the per-sample kernels).
struct SymD {
  double xx, yy, zz, xy, xz, yz;
  explicit SymD(const Sggx& s) : xx(s.xx), yy(s.yy), zz(s.zz), xy(s.xy), xz(s.xz), yz(s.yz) {}
  double det() const { return xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz); }
};

Vec3d to_d(const Vec3& v) { return Vec3d(v.x, v.y, v.z); }

// The cofactor matrix adj(S) and |S| in double (see the header): the product of two floats is exact in double,
// so the 2x2 minors of a thin S — O(σ²) differences of O(1) products — and |S| = O(σ⁴) keep their digits, and
// so do the quadratic forms ωᵀ adj(S) ω, whose condition number is 1/σ². Tried in float, the normalisation
// tests fail already on the surface rows (σ 0.05–0.3): ∫D_ωi = 1 + 1.3e-5 against a tolerance of 2e-6.
struct Cofactors {
  double a00, a11, a22, a01, a02, a12, det;
  explicit Cofactors(const Sggx& s) {
    const double xx = s.xx, yy = s.yy, zz = s.zz, xy = s.xy, xz = s.xz, yz = s.yz;
    a00 = yy * zz - yz * yz;
    a11 = xx * zz - xz * xz;
    a22 = xx * yy - xy * xy;
    a01 = xz * yz - xy * zz;
    a02 = xy * yz - xz * yy;
    a12 = xy * xz - xx * yz;
    det = xx * a00 + xy * a01 + xz * a02;
  }
  // aᵀ adj(S) b.
  double bilinear(const Vec3& a, const Vec3& b) const {
    const double ax = a.x, ay = a.y, az = a.z, bx = b.x, by = b.y, bz = b.z;
    return ax * (a00 * bx + a01 * by + a02 * bz) + ay * (a01 * bx + a11 * by + a12 * bz) +
           az * (a02 * bx + a12 * by + a22 * bz);
  }
  double quadratic(const Vec3& w) const {
    const double x = w.x, y = w.y, z = w.z;
    return a00 * x * x + a11 * y * y + a22 * z * z + 2.0 * (a01 * x * y + a02 * x * z + a12 * y * z);
  }
};

// The MIS proxy's fixed rule on the visible disk: U1 at the 2-point Gauss–Legendre nodes of [0, 1], four
// azimuths per ring, the second ring turned by π/4. Equal weights 1/8. Each point as (u, v, w) of step 6.
struct DiskRule {
  std::array<float, 8> u{}, v{}, w{};
  DiskRule() {
    const double u1[2] = {0.5 - 0.5 / std::sqrt(3.0), 0.5 + 0.5 / std::sqrt(3.0)};
    for (size_t ring = 0; ring < 2; ++ring)
      for (size_t k = 0; k < 4; ++k) {
        const double r = std::sqrt(u1[ring]);
        const double phi = 2.0 * kPiD * (double(k) + 0.5 * double(ring)) / 4.0;
        u[4 * ring + k] = static_cast<float>(r * std::cos(phi));
        v[4 * ring + k] = static_cast<float>(r * std::sin(phi));
        w[4 * ring + k] = static_cast<float>(std::sqrt(1.0 - u1[ring]));
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

Sggx regularized(const Sggx& S) {
  const double trace = std::max(S.xx, 0.0f) + std::max(S.yy, 0.0f) + std::max(S.zz, 0.0f);
  const double r2 = double(kMinRoughness) * kMinRoughness;
  // A surface of roughness r and trace t has |S| ≈ r⁴ t³; a fiber's is far larger.
  if (Cofactors(S).det > r2 * r2 * trace * trace * trace / 64.0) return S;
  const float e = static_cast<float>(r2 * trace);
  return {S.xx + e, S.yy + e, S.zz + e, S.xy, S.xz, S.yz};
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
  // In double: ωᵀSω is O(σ²) along a thin axis, from O(1) terms; in float it loses ε/σ² relative
  // (2.3e-6 at σ = 0.06, failing Sggx.ProjectedAreaIsIntegralOfD's 2e-6). The products are exact in double.
  const double x = w.x, y = w.y, z = w.z;
  const double q = S.xx * x * x + S.yy * y * y + S.zz * z * z +
                   2.0 * (double(S.xy) * x * y + double(S.xz) * x * z + double(S.yz) * y * z);
  return std::sqrt(std::max(static_cast<float>(q), 0.0f));  // eq. (11); the square root is well conditioned
}

float max_projected_area(const Sggx& S) {
  return static_cast<float>(std::sqrt(std::max(eigenvalues(to_matrix(S))[0], 0.0)));
}

// ωmᵀ S⁻¹ ωm = ωmᵀ adj(S) ωm / |S|, so eq. (12) is |S|^{3/2} / (π (ωmᵀ adj(S) ωm)²): Ndf's formula, once.
float D(const Sggx& S, const Vec3& wm) { return Ndf(S)(wm); }

Ndf::Ndf(const Sggx& S) {
  const Cofactors A(S);
  if (!(A.det > 0.0)) return;  // singular: D = 0
  adj_ = {A.a00, A.a11, A.a22, A.a01, A.a02, A.a12};
  scale_ = A.det * std::sqrt(A.det) / kPiD;  // eq. (12)
}

float D_visible(const Sggx& S, const Vec3& wi, const Vec3& wm) {
  const float cos_im = glm::dot(wi, wm);
  if (cos_im <= 0.0f) return 0.0f;
  const float sigma = projected_area(S, wi);
  return sigma > 0.0f ? cos_im * D(S, wm) / sigma : 0.0f;  // eq. (21)
}

// Algorithm 1, steps 2–4. Instead of projecting S onto the basis (ωk, ωj, ωi) and forming its minors there,
// the minors come from adj(S): the minor of S on span(ωj, ωi) is ωkᵀ adj(S) ωk (ωk = ωj × ωi), its cross
// cofactor S_ki S_ji − S_kj S_ii is ωkᵀ adj(S) ωj, and |S^kji| = |S| — invariants of the rotation, computed
// once from the six coefficients.
VisibleNormals::VisibleNormals(const Sggx& S, const Vec3& wi) {
  Vec3 wk, wj;
  orthonormal_basis(wi, wk, wj);  // step 2 (right-handed: ωk × ωj = ωi)
  const Cofactors A(S);
  const double minor = A.quadratic(wk);
  // S ωi and S_ii = σ²(ωi) in double: for ωi along a thin fiber σ² is O(σ²) from O(1) terms.
  const double wx = wi.x, wy = wi.y, wz = wi.z;
  const Vec3d s_wi(S.xx * wx + S.xy * wy + S.xz * wz, S.xy * wx + S.yy * wy + S.yz * wz,
                   S.xz * wx + S.yz * wy + S.zz * wz);
  const double S_ii = wx * s_wi.x + wy * s_wi.y + wz * s_wi.z;
  if (!(S_ii > 0.0) || !(minor > 0.0) || !(A.det > 0.0)) return;
  // Step 4: M_k = (sqrt(|S|/minor), 0, 0), M_j = (−(S_ki S_ji − S_kj S_ii), minor, 0) / sqrt(S_ii minor),
  // M_i = (S_ki, S_ji, S_ii) / sqrt(S_ii); c = the columns rotated back to world space. Step 6 normalises
  // u ck + v cj + w ci, so one common factor of the columns does not matter: all three are multiplied by
  // sqrt(S_ii minor), which leaves two independent square roots and no division on this latency chain.
  const Vec3d wk_d(wk), wj_d(wj);
  ck = std::sqrt(A.det * S_ii) * wk_d;
  cj = -A.bilinear(wk, wj) * wk_d + minor * wj_d;
  ci = std::sqrt(minor) * s_wi;
  valid = true;
}

Vec3 VisibleNormals::normal(float u_f, float v_f) const {
  // In double: for a near-singular S (a voxel holding one flat leaf) the three columns nearly cancel.
  const double u = u_f, v = v_f, w = std::sqrt(std::max(0.0, 1.0 - u * u - v * v));  // step 6
  const Vec3d m = u * ck + v * cj + w * ci;
  return Vec3(m * (1.0 / std::sqrt(glm::dot(m, m))));
}

Vec3 VisibleNormals::sample(const Vec2& u) const {
  const Vec2 p = warp::square_to_disk_concentric(u);  // step 5, see the header's deviations
  return normal(p.x, p.y);
}

Vec3 sample_visible(const Sggx& S, const Vec3& wi, const Vec2& u) {
  const VisibleNormals map(S, wi);
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

Vec3 principal_axis(const Sggx& S) {
  const SymmetricEigen e = eigen(S);
  const double gap_top = e.values[0] - e.values[1], gap_bottom = e.values[1] - e.values[2];
  // Below a relative gap of 1e-3 both ways S is a sphere's (or its axes are undecided): no axis.
  if (!(std::max(gap_top, gap_bottom) > 1e-3 * e.values[0])) return Vec3(0.0f);
  const Vec3d v = gap_top > gap_bottom ? e.vectors[0] : e.vectors[2];
  int largest = 0;
  for (int k = 1; k < 3; ++k)
    if (std::abs(v[k]) > std::abs(v[largest])) largest = k;
  return Vec3(v[largest] < 0.0 ? -v : v);
}

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

namespace {
// decompress()'s test: R = [[1, r0, r1], [r0, 1, r2], [r1, r2, 1]] positive definite with λ_min ≥ kCompactMinEigen
// (det R ≥ 9 δ suffices, λ ≤ 3); otherwise the exact smallest eigenvalue decides.
bool guard_passes(const double r[3]) {
  const double det_r = 1.0 + 2.0 * r[0] * r[1] * r[2] - r[0] * r[0] - r[1] * r[1] - r[2] * r[2];
  if (1.0 - r[0] * r[0] > 0.0 && det_r >= 9.0 * kCompactMinEigen) return true;
  return eigenvalues({{{1.0, r[0], r[1]}, {r[0], 1.0, r[2]}, {r[1], r[2], 1.0}}})[2] >= kCompactMinEigen;
}
}  // namespace

bool correlations_pass_guard(const SggxCompact& c) {
  const double r[3] = {c.r[0] / 127.0, c.r[1] / 127.0, c.r[2] / 127.0};
  return guard_passes(r);
}

SggxCompact compress_spd(const Sggx& S, float sigma_scale) {
  SggxCompact c = compress(S, sigma_scale);
  const std::array<int8_t, 3> q = c.r;
  // Shrinking every r by one factor k moves R towards I (eigenvalues 1 + k μ); truncation shrinks each a
  // little more, so the loop may step past the smallest k that works, never short of passing (k = 0 is I).
  for (double k = 1.0; !correlations_pass_guard(c); k -= 1.0 / 128.0)
    for (size_t a = 0; a < 3; ++a) c.r[a] = static_cast<int8_t>(std::trunc(q[a] * std::max(k, 0.0)));
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
  return D_.eval_unnormalised(h, len2) / (4.0f * sigma);  // eq. (24)
}

PhaseSample SggxSpecularPhase::sample(const Vec3& wo, const Vec2& u, Pcg32&) const {
  const Vec3 wm = sggx::sample_visible(S_, wo, u);
  PhaseSample s;
  s.wi = glm::normalize(reflect(wo, wm));  // §5.3: mirror wo about the visible normal
  s.pdf = pdf(wo, s.wi);
  s.f = s.pdf;  // the sampling density is f_p itself
  return s;
}

const sggx::VisibleNormals& SggxDiffusePhase::visible_normals(const Vec3& wo) const {
  if (cache_ != Cache::Empty && wo == cached_wo_) return map_;
  map_ = sggx::VisibleNormals(S_, wo);
  cached_wo_ = wo;
  cache_ = Cache::Map;
  return map_;
}

float SggxDiffusePhase::eval(const Vec3& wo, const Vec3& wi, Pcg32& rng) const {
  const sggx::VisibleNormals& map = visible_normals(wo);
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
  const sggx::VisibleNormals& map = visible_normals(wo);
  if (!map.valid) return kInv4Pi;
  // The rule's normals m_j = u_j ck + v_j cj + w_j ci do not depend on wi: their inverse lengths are kept
  // with the map, and ⟨wi, m_j⟩ = u_j ⟨wi, ck⟩ + v_j ⟨wi, cj⟩ + w_j ⟨wi, ci⟩ costs three dot products.
  if (cache_ != Cache::MapAndProxy) {
    for (size_t j = 0; j < 8; ++j) {
      const double u = kDiskRule.u[j], v = kDiskRule.v[j], w = kDiskRule.w[j];
      const Vec3d m = u * map.ck + v * map.cj + w * map.ci;  // double: see VisibleNormals::normal
      inv_len_[j] = static_cast<float>(1.0 / std::sqrt(glm::dot(m, m)));
    }
    // In float, scaled to unit size (the columns carry |S|^{3/2}, which float may not hold).
    const double scale = 1.0 / std::max({glm::length(map.ck), glm::length(map.cj), glm::length(map.ci)});
    ck_ = Vec3(map.ck * scale);
    cj_ = Vec3(map.cj * scale);
    ci_ = Vec3(map.ci * scale);
    for (float& l : inv_len_) l = static_cast<float>(l / scale);
    cache_ = Cache::MapAndProxy;
  }
  const float dk = glm::dot(wi, ck_), dj = glm::dot(wi, cj_), di = glm::dot(wi, ci_);
  float sum = 0.0f;
  for (size_t j = 0; j < 8; ++j)
    sum += std::max((kDiskRule.u[j] * dk + kDiskRule.v[j] * dj + kDiskRule.w[j] * di) * inv_len_[j], 0.0f);
  return (1.0f - kProxyUniform) * sum * (kInvPi / 8.0f) + kProxyUniform * kInv4Pi;
}

PhaseSample SggxDiffusePhase::sample(const Vec3& wo, const Vec2& u, Pcg32& rng) const {
  const sggx::VisibleNormals& map = visible_normals(wo);
  const Vec3 wm = map.valid ? map.sample(u) : wo;
  const float u1 = rng.next_float();
  const Vec3 local = warp::square_to_cosine_hemisphere(Vec2(u1, rng.next_float()));
  PhaseSample s;
  s.wi = glm::normalize(Frame(wm).to_world(local));  // §5.3: Lambertian reflection off the visible flake
  s.pdf = pdf(wo, s.wi);  // the MIS proxy
  s.f = s.pdf;            // weight 1: eq. (25) is sampled exactly
  return s;
}

}  // namespace kozu
