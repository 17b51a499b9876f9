// sggx: the symmetric GGX (SGGX) microflake distribution — an ellipsoid's normal distribution given by the
// 3x3 SPD matrix S of its squared projected areas — with its projected area, NDF, visible normals and their
// exact sampling, the specular and diffuse microflake phase functions, parameter estimation, compact storage
// and interpolation.
//
// Citation: Heitz, Dupuy, Crassin & Dachsbacher 2015, "The SGGX Microflake Distribution", ACM Transactions on Graphics
// 34(4) (SIGGRAPH 2015); equations numbered (1)–(26) as in the paper.
//
// Equation map
//   Sggx (six coefficients)           S in the canonical basis                      eq. (10)
//   from_basis                        S = Σ σ_k² ω_k ω_kᵀ                           eq. (9)
//   surface(n, σ)                     eigenvalues (σ², σ², 1), ω3 = n               eq. (13), (14)
//   fiber(t, σ)                       eigenvalues (1, 1, σ²), ω3 = t                eq. (15), (16)
//   projected_area σ(ω)               sqrt(ωᵀ S ω) (= ∫⟨ω, ωm⟩ D dωm, eq. 4)        eq. (11)
//   D(ωm), Ndf                        1 / (π sqrt|S| (ωmᵀ S⁻¹ ωm)²)                 eq. (12)
//   D_visible(ωi, ωm)                 ⟨ωi, ωm⟩ D(ωm) / σ(ωi)                        eq. (21), normalised by (22)
//   sample_visible, VisibleNormals    Algorithm 1 (ellipsoid's visible hemisphere)
//   SggxSpecularPhase::eval / pdf     D(ωh) / (4 σ(ωi))                              eq. (24)
//   SggxSpecularPhase::sample         ωm ~ D_ωi (Alg. 1), mirror ωi about ωm        §5.3
//   SggxDiffusePhase (exact value)    (1/π) ∫⟨ωo, ωm⟩ D_ωi(ωm) dωm                  eq. (25)
//   SggxDiffusePhase::eval            (1/N) Σ_j (1/π)⟨ωo, ωm(j)⟩, ωm(j) ~ D_ωi       eq. (26)
//   SggxDiffusePhase::sample          ωm ~ D_ωi, then ωo cosine-distributed about ωm §5.3
//   estimate, estimate_from_normals   covariance Σ, its eigenvectors, σ along them  eq. (17), (18), (9)
//   compress / decompress             (σx, σy, σz, rxy, rxz, ryz) in 6 bytes        eq. (19), (20)
//   lerp                              linear in the six coefficients of S           §4.4
// Here ωi of the paper is `wo` of phase.h (the given direction) and the paper's ωo is the sampled `wi`.
//
// Parameters
//   name              type    default      range        meaning
//   S (Sggx)          6 x f32 identity     SPD          squared projected areas; any positive scale (D is not
//                                                       normalised, §4.1 obs. 2; σ scales the density)
//   roughness         f32     —            ≥ 1e-3       surface / fiber: σ of the tangents / of the tangent
//                                                       axis (clamped below to kMinRoughness; σ = 1 is a sphere)
//   estimator_samples int     1            ≥ 1          N of eq. (26) for SggxDiffusePhase::eval
//   sigma_scale       f32     1            > 0          compact form: σx,y,z are stored relative to it
//
// Deviations and implementation choices
//   - Precision. The kernels take and return floats and run in float except where a test showed float fails;
//     there the float inputs are widened first, which makes the products of two of them exact:
//       * adj(S) and |S| (D, Ndf, Algorithm 1's minors): for a thin surface or fiber they are O(σ²) and
//         O(σ⁴) differences of O(1) products, and the quadratic forms ωᵀ adj(S) ω have condition number
//         1/σ². Tried in float, Sggx.VisibleNormalsAndSpecularPhaseNormalised and
//         ProjectedAreaIsIntegralOfD fail already on the surface rows (σ 0.05–0.3; ∫D_ωi − 1 = 1.3e-5
//         against 2e-6).
//       * ωᵀSω in σ(ω) and Algorithm 1's S_ii: O(σ²) along a thin axis from O(1) terms; float loses ε/σ²
//         relative (2.3e-6 at σ = 0.06, failing Sggx.ProjectedAreaIsIntegralOfD's 2e-6).
//     Square roots of the results, the basis, Algorithm 1's steps 5–6 and the phase functions' remaining
//     arithmetic are float. Algorithm 1's step 4 uses the rotation invariants of adj(S) instead of projecting
//     S onto the basis first (see VisibleNormals). Tested down to roughness 1e-3 (the SggxThin rows).
//   - Compact storage: σx,y,z = sqrt(Sxx,yy,zz) / sigma_scale clamped to [0, 1] and rounded to 8 bits
//     (step sigma_scale/255); r's rounded to signed 8 bits r = q/127, q in [−127, 127] (step 1/127, r = 0
//     exact, error ≤ 1/254). Decompression applies eq. (20) and then, only when the quantised correlation
//     matrix R (unit diagonal, off-diagonals r) has lost positive definiteness (possible when S is
//     nearly singular: the r's of a σ < 0.06 surface are within a quantisation step of the boundary), shrinks
//     R's off-diagonals by one common factor so that its smallest eigenvalue is kCompactMinEigen. sigma_scale
//     is per grid: the largest sqrt(Sxx), sqrt(Syy), sqrt(Szz) over the voxels (1 for surface/fiber data).
//   - Algorithm 1 step 5 draws the uniform point of the visible disk with the concentric map (Shirley & Chiu
//     1997, warp::square_to_disk_concentric) instead of sqrt(U1)(cos 2πU2, sin 2πU2): the same distribution,
//     without the sine and cosine, and with less distortion for stratified u.
//   - SggxDiffusePhase::pdf has no closed form; it returns a deterministic proxy for MIS only: the same
//     estimator as eval with the N random visible normals replaced by a fixed 8-point rule on Algorithm 1's
//     visible disk (2 Gauss–Legendre nodes in U1 = r², 4 equally spaced azimuths), mixed with 1/16 of the
//     uniform density so that it is positive wherever the sampler can land. It is itself a normalised density
//     (a mixture of clamped-cosine lobes and the uniform sphere), costs one Algorithm-1 setup, and follows the
//     phase's shape (cosine about the normal for a surface, a band for a fiber), unlike the specular closed
//     form, whose lobe is a mirror lobe. sample() returns weight 1 (it samples eq. 25 exactly, §5.3) and this
//     proxy as pdf. The proxy's eight normals depend on wo only: the phase keeps Algorithm 1's setup and
//     their inverse lengths for the last wo, so a pdf for a new wi costs three dot products and eight
//     multiply-adds (a scattering vertex calls sample, eval and pdf with one wo).
//   - estimate() integrates with a product Gauss–Legendre rule in (θ, φ) (uniform in angle, so a peaked D is
//     resolved equally well in any orientation); the projected areas are integrated in a frame whose pole is
//     the eigenvector, which puts the clamp ⟨ω, ωm⟩ on a cell edge.
//   - A degenerate input (a single plane of normals, roughness 0) yields a singular S; is_spd() says so.
#pragma once

#include "core/math.h"
#include "core/rng.h"
#include "media/phase.h"

#include <array>
#include <cstdint>
#include <functional>
#include <span>

namespace kozu {

// A symmetric positive definite 3x3 matrix S by its six coefficients (eq. 10). Media store, interpolate
// and filter these six numbers linearly, never the compact form (§4.3).
struct Sggx {
  float xx = 1, yy = 1, zz = 1, xy = 0, xz = 0, yz = 0;

  Sggx operator*(float s) const { return {xx * s, yy * s, zz * s, xy * s, xz * s, yz * s}; }
  Sggx operator+(const Sggx& o) const { return {xx + o.xx, yy + o.yy, zz + o.zz, xy + o.xy, xz + o.xz, yz + o.yz}; }
};

// A weighted unit normal (an oriented surface element of area `weight`), the input of estimate_from_normals.
struct WeightedNormal {
  Vec3 n;
  float weight;
};

// Compact 6-byte storage of S (eq. 19): σ's relative to a per-grid scale in 8 bits, r's in signed 8 bits.
struct SggxCompact {
  std::array<uint8_t, 3> sigma{};  // round(255 · sqrt(S_aa) / sigma_scale), a = x, y, z
  std::array<int8_t, 3> r{};       // round(127 · r_ab), (ab) = xy, xz, yz
};
static_assert(sizeof(SggxCompact) == 6);

namespace sggx {

// Roughness below this is clamped by surface() and fiber(): σ = 0 would make S singular.
inline constexpr float kMinRoughness = 1e-3f;
// Smallest eigenvalue decompress() lets the quantised correlation matrix keep (see the header's deviations).
inline constexpr float kCompactMinEigen = 1e-4f;

// ---- construction --------------------------------------------------------------------------------------

// S = σ1² ω1 ω1ᵀ + σ2² ω2 ω2ᵀ + σ3² ω3 ω3ᵀ for an orthonormal basis (ω1, ω2, ω3) and the projected areas
// σ_k = σ(ω_k) along it (eq. 9). The σ's are projected areas, not their squares.
Sggx from_basis(const Vec3& w1, const Vec3& w2, const Vec3& w3, float sigma1, float sigma2, float sigma3);
// A surface-like distribution about the unit normal n with roughness σ (eq. 13–14): σ(n) = 1 and σ = σ along
// the tangents. σ is GGX's α; σ → 0 is a flat disk (a delta NDF), σ = 1 the sphere.
Sggx surface(const Vec3& normal, float roughness);
// A fiber-like distribution about the unit tangent t (eq. 15–16): σ(t) = σ and 1 across it; σ → 0 is a
// cylinder (normals in the plane ⟂ t), σ = 1 the sphere.
Sggx fiber(const Vec3& tangent, float roughness);
// S itself, or S + kMinRoughness² tr(S) I where S is thinner than surface() allows (|S| below that of a
// roughness-kMinRoughness surface of the same trace, by a margin of 64: a voxel holding one flat leaf has the
// singular S = n nᵀ, 65 % of the bush's voxels), so that D, its visible normals and both phase functions are
// defined and agree there. The phase functions apply it.
Sggx regularized(const Sggx& S);
// R S Rᵀ for an orthogonal R: the distribution turned by R (σ_RSRᵀ(Rω) = σ_S(ω)).
Sggx rotated(const Sggx& S, const Mat3& R);

// ---- evaluation ----------------------------------------------------------------------------------------

// σ(ω) = sqrt(ωᵀ S ω), the projected area (eq. 11).
float projected_area(const Sggx& S, const Vec3& w);
// The largest projected area over all directions: sqrt of S's largest eigenvalue (majorants).
float max_projected_area(const Sggx& S);
// The NDF D(ωm) of eq. 12 (unnormalised: ∫ D ≠ 1 in general; D(−ωm) = D(ωm)). 0 for a singular S.
float D(const Sggx& S, const Vec3& wm);
// D for one S evaluated many times (a phase function at one scattering vertex): adj(S) and |S|^{3/2}/π kept,
// so that each call is one quadratic form and one division.
class Ndf {
 public:
  Ndf() = default;
  explicit Ndf(const Sggx& S);
  float operator()(const Vec3& wm) const { return eval_unnormalised(wm, 1.0f); }
  // D(w / |w|) for any w ≠ 0 given |w|² (the half vector unnormalised): D is homogeneous of degree −4 in w.
  float eval_unnormalised(const Vec3& w, float len2) const {
    const double x = w.x, y = w.y, z = w.z;
    const double q = adj_[0] * x * x + adj_[1] * y * y + adj_[2] * z * z +
                     2.0 * (adj_[3] * x * y + adj_[4] * x * z + adj_[5] * y * z);
    const double l2 = len2;
    return q > 0.0 ? static_cast<float>(scale_ * l2 * l2 / (q * q)) : 0.0f;
  }

 private:
  std::array<double, 6> adj_{};  // adj(S): xx, yy, zz, xy, xz, yz (double: see the header's deviations)
  double scale_ = 0.0;           // |S|^{3/2} / π
};
// The distribution of visible normals D_ωi(ωm) = ⟨ωi, ωm⟩ D(ωm) / σ(ωi) (eq. 21); a pdf in ωm (eq. 22).
float D_visible(const Sggx& S, const Vec3& wi, const Vec3& wm);
// Samples D_ωi by Algorithm 1 from u in [0, 1)²; the result has ⟨ωi, ωm⟩ ≥ 0.
Vec3 sample_visible(const Sggx& S, const Vec3& wi, const Vec2& u);

// Algorithm 1 split at step 4: the per-ωi setup (the world-space columns ck, cj, ci of M, up to one common
// positive factor), then any number of visible normals normalize(u ck + v cj + w ci) for points of the unit
// disk. valid is false for a singular S.
struct VisibleNormals {
  Vec3d ck{0.0}, cj{0.0}, ci{0.0};
  bool valid = false;
  VisibleNormals() = default;
  VisibleNormals(const Sggx& S, const Vec3& wi);
  // Step 6 for a point (u, v) of the unit disk.
  Vec3 normal(float u, float v) const;
  // Steps 5 and 6 from u in [0, 1)².
  Vec3 sample(const Vec2& u) const;
};

// ---- linear algebra ------------------------------------------------------------------------------------

// Eigen-decomposition of a symmetric 3x3 matrix by cyclic Jacobi rotations in double precision (robust for
// repeated eigenvalues: any orthonormal basis of a repeated eigenspace is returned). values[k] belongs to
// vectors[k]; sorted by decreasing value; vectors orthonormal and right-handed.
struct SymmetricEigen {
  std::array<double, 3> values{};
  std::array<Vec3d, 3> vectors{};
};
SymmetricEigen eigen(const std::array<std::array<double, 3>, 3>& m);
SymmetricEigen eigen(const Sggx& S);

// The axis that sets S apart, signed so that its largest component is positive (a fiber's two directions are one):
// the eigenvector of the eigenvalue farthest from the other two, the fiber's tangent where S is fiber-like (eqs.
// 15-16: eigenvalues 1, 1, σ²) and the flakes' normal where it is surface-like (σ², σ², 1); zero where S is
// isotropic. The denoiser's normal feature in SGGX media (render/aov.h): it tells warp from weft.
Vec3 principal_axis(const Sggx& S);

// True when S is symmetric positive definite (Sylvester's criterion in double precision) and finite.
bool is_spd(const Sggx& S);
// (1 − t) a + t b on the six coefficients: a convex combination of SPD matrices is SPD, and σ²(ω) of the
// result is the same combination of the inputs' σ²(ω) (§4.4).
Sggx lerp(const Sggx& a, const Sggx& b, float t);

// ---- parameter estimation (eq. 17–18) ------------------------------------------------------------------

// Fits S to an arbitrary (unnormalised) symmetric distribution of normals D(ωm) = D(−ωm): the covariance Σ
// of eq. 18 by quadrature, its eigenvectors ω_k, the projected areas σ(ω_k) = ∫⟨ω_k, ωm⟩ D dωm (eq. 17), and
// S by eq. 9. Exact (up to the quadrature) when D is itself SGGX. The quadrature has `resolution` cells in θ
// by 2·resolution in φ with 4x4 Gauss–Legendre points each; D should vary little over 1/resolution rad
// (resolution ≥ ~4/σ_min for an SGGX-like input of roughness σ_min).
Sggx estimate(const std::function<double(const Vec3&)>& D, int resolution);
// Eq. (17–18) for a discrete distribution of surface elements: covariance of the normals, its eigenvectors,
// projected areas Σ w |ω_k · n| / Σ w along them, S = Σ σ_k² ω_k ω_kᵀ. Exact when the input is SGGX-like.
Sggx estimate_from_normals(std::span<const WeightedNormal> normals);

// ---- compact storage (eq. 19–20) -----------------------------------------------------------------------

SggxCompact compress(const Sggx& S, float sigma_scale = 1.0f);
// Eq. 20, plus the positive-definiteness guard described in the header.
Sggx decompress(const SggxCompact& c, float sigma_scale = 1.0f);
// compress(), then the r codes moved towards 0 (all by one factor, rounded towards 0) until the quantised
// correlation matrix passes decompress()'s guard unchanged: what voxel grids store, so that their lookups
// can use eq. 20 alone (decompress_unguarded).
SggxCompact compress_spd(const Sggx& S, float sigma_scale = 1.0f);
// Eq. 20 without the guard (for codes from compress_spd); what a voxel lookup costs: six products.
inline Sggx decompress_unguarded(const SggxCompact& c, float sigma_scale) {
  const float k = sigma_scale * (1.0f / 255.0f);
  const float sx = c.sigma[0] * k, sy = c.sigma[1] * k, sz = c.sigma[2] * k;
  constexpr float kr = 1.0f / 127.0f;
  return {sx * sx, sy * sy, sz * sz, c.r[0] * kr * sx * sy, c.r[1] * kr * sx * sz, c.r[2] * kr * sy * sz};
}
// True when decompress()'s guard leaves c's correlations as they are.
bool correlations_pass_guard(const SggxCompact& c);

}  // namespace sggx

// ---- phase functions (conventions of phase.h: wo given, wi sampled, f_p per unit solid angle of wi) ------

// Specular microflakes (eq. 24): f_p(wo, wi) = D(ωh) / (4 σ(wo)), ωh = (wo + wi)/|wo + wi|. Deterministic:
// pdf = eval, sample returns weight 1.
class SggxSpecularPhase final : public PhaseFunction {
 public:
  explicit SggxSpecularPhase(const Sggx& S) : S_(sggx::regularized(S)), D_(S_) {}
  float eval(const Vec3& wo, const Vec3& wi, Pcg32& rng) const override;
  PhaseSample sample(const Vec3& wo, const Vec2& u, Pcg32& rng) const override;
  float pdf(const Vec3& wo, const Vec3& wi) const override;
  Vec3 feature_axis() const override { return sggx::principal_axis(S_); }
  const Sggx& matrix() const { return S_; }

 private:
  Sggx S_;
  sggx::Ndf D_;
};

// Diffuse (Lambertian) microflakes (eq. 25). eval is the unbiased estimate of eq. 26 with
// `estimator_samples` visible normals drawn with rng (default 1, as in the paper's renderer); sample draws a
// visible normal with u and a cosine direction about it with rng (exact: weight 1); pdf is the deterministic
// MIS proxy described in the header.
class SggxDiffusePhase final : public PhaseFunction {
 public:
  explicit SggxDiffusePhase(const Sggx& S, int estimator_samples = 1)
      : S_(sggx::regularized(S)), samples_(estimator_samples < 1 ? 1 : estimator_samples) {}
  float eval(const Vec3& wo, const Vec3& wi, Pcg32& rng) const override;
  PhaseSample sample(const Vec3& wo, const Vec2& u, Pcg32& rng) const override;
  float pdf(const Vec3& wo, const Vec3& wi) const override;
  Vec3 feature_axis() const override { return sggx::principal_axis(S_); }
  const Sggx& matrix() const { return S_; }
  int estimator_samples() const { return samples_; }

 private:
  // Algorithm 1's setup for the last wo, and the MIS proxy's inverse normal lengths for it: a scattering
  // vertex asks for eval, sample and pdf with the same wo. Not thread-safe: phases live in one thread's arena.
  enum class Cache { Empty, Map, MapAndProxy };
  const sggx::VisibleNormals& visible_normals(const Vec3& wo) const;

  Sggx S_;
  int samples_;
  mutable Cache cache_ = Cache::Empty;
  mutable Vec3 cached_wo_{0.0f};
  mutable sggx::VisibleNormals map_;
  mutable std::array<float, 8> inv_len_{};
  mutable Vec3 ck_{0.0f}, cj_{0.0f}, ci_{0.0f};  // map_'s columns in float, for the proxy's dot products
};

}  // namespace kozu
