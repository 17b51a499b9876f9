#include "materials/ltc_table.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace kozu {

namespace {

const LtcTableEntry kGgx[kLtcTableSize * kLtcTableSize] = {
#include "materials/ltc_ggx_data.inc"
};
const LtcTableEntry kBeckmann[kLtcTableSize * kLtcTableSize] = {
#include "materials/ltc_beckmann_data.inc"
};
const LtcTableEntry kGgxCompensated[kLtcTableSize * kLtcTableSize] = {
#include "materials/ltc_ggx_compensated_data.inc"
};
const LtcTableEntry kBeckmannCompensated[kLtcTableSize * kLtcTableSize] = {
#include "materials/ltc_beckmann_compensated_data.inc"
};
const LtcTableEntry kGgxSpecular[kLtcTableSize * kLtcTableSize] = {
#include "materials/ltc_ggx_specular_data.inc"
};
const LtcTableEntry kBeckmannSpecular[kLtcTableSize * kLtcTableSize] = {
#include "materials/ltc_beckmann_specular_data.inc"
};

const LtcTableEntry* table(LtcBrdf brdf) {
  switch (brdf) {
    case LtcBrdf::Ggx:
      return kGgx;
    case LtcBrdf::Beckmann:
      return kBeckmann;
    case LtcBrdf::GgxCompensated:
      return kGgxCompensated;
    case LtcBrdf::BeckmannCompensated:
      return kBeckmannCompensated;
    case LtcBrdf::GgxSpecular:
      return kGgxSpecular;
    case LtcBrdf::BeckmannSpecular:
      return kBeckmannSpecular;
  }
  return kGgx;
}

}  // namespace

const char* ltc_brdf_name(LtcBrdf brdf) {
  switch (brdf) {
    case LtcBrdf::Ggx:
      return "ggx";
    case LtcBrdf::Beckmann:
      return "beckmann";
    case LtcBrdf::GgxCompensated:
      return "ggx-compensated";
    case LtcBrdf::BeckmannCompensated:
      return "beckmann-compensated";
    case LtcBrdf::GgxSpecular:
      return "ggx-specular";
    case LtcBrdf::BeckmannSpecular:
      return "beckmann-specular";
  }
  return "?";
}

const LtcTableEntry& ltc_table_entry(LtcBrdf brdf, int i, int j) {
  const LtcTableEntry* t = table(brdf);
  return t[std::clamp(i, 0, kLtcTableSize - 1) * kLtcTableSize + std::clamp(j, 0, kLtcTableSize - 1)];
}

namespace {

// The entry's six numbers (M⁻¹'s four, the norm, the Fresnel norm), bilinear in (θ_v, √α).
std::array<float, 6> interpolate(LtcBrdf brdf, float cos_theta_v, float alpha) {
  constexpr float kLast = kLtcTableSize - 1;
  // The grid of kozu fit-ltc (tools/ltc_fit.h): θ_v = j/(N − 1) · π/2, α = (i/(N − 1))².
  // The last column is θ_v = 1.57, not π/2 (tools/ltc_fit.h: the view must stay above the horizon).
  const float theta = std::acos(std::clamp(cos_theta_v, 0.0f, 1.0f));
  const float theta_before_last = (kLast - 1.0f) / kLast * 0.5f * kPi;
  const float x = theta <= theta_before_last
                      ? theta / (0.5f * kPi) * kLast
                      : std::min(kLast, kLast - 1.0f + (theta - theta_before_last) / (1.57f - theta_before_last));
  const float y = std::clamp(std::sqrt(std::max(alpha, 0.0f)), 0.0f, 1.0f) * kLast;
  const int j = std::min(static_cast<int>(x), kLtcTableSize - 2), i = std::min(static_cast<int>(y), kLtcTableSize - 2);
  const float tx = x - static_cast<float>(j), ty = y - static_cast<float>(i);
  std::array<float, 6> v{};
  for (int di = 0; di < 2; ++di)
    for (int dj = 0; dj < 2; ++dj) {
      const LtcTableEntry& e = ltc_table_entry(brdf, i + di, j + dj);
      const float w = (di ? ty : 1.0f - ty) * (dj ? tx : 1.0f - tx);
      const float entry[6] = {e.m00, e.m02, e.m11, e.m20, e.norm, e.fresnel_norm};
      for (int k = 0; k < 6; ++k) v[k] += w * entry[k];
    }
  return v;
}

// The interpolated M⁻¹ (in the view's frame) and norms of ltc_lookup, before the Ltc is built from them.
Mat3 lookup_inverse(LtcBrdf brdf, float cos_theta_v, float alpha, float* norm, float* fresnel_norm) {
  const std::array<float, 6> v = interpolate(brdf, cos_theta_v, alpha);
  Mat3 m_inv(0.0f);  // glm: [column][row]
  m_inv[0][0] = v[0];
  m_inv[2][0] = v[1];
  m_inv[1][1] = v[2];
  m_inv[0][2] = v[3];
  m_inv[2][2] = 1.0f;
  *norm = v[4];
  *fresnel_norm = v[5];
  return m_inv;
}

}  // namespace

void ltc_norms(LtcBrdf brdf, float cos_theta_v, float alpha, float* norm, float* fresnel_norm) {
  const std::array<float, 6> v = interpolate(brdf, cos_theta_v, alpha);
  *norm = v[4];
  *fresnel_norm = v[5];
}

LtcLobeFit ltc_lookup(LtcBrdf brdf, float cos_theta_v, float alpha) {
  LtcLobeFit fit;
  fit.ltc = Ltc::from_inverse(lookup_inverse(brdf, cos_theta_v, alpha, &fit.norm, &fit.fresnel_norm));
  return fit;
}

LtcLobeFit ltc_lobe(LtcBrdf brdf, const Vec3& wo, float alpha) {
  LtcLobeFit fit;
  const Mat3 m_inv = lookup_inverse(brdf, wo.z, alpha, &fit.norm, &fit.fresnel_norm);
  // R takes the shading frame to the view's: its x axis is wo's azimuth (any, for a view along the normal).
  const float r = std::sqrt(wo.x * wo.x + wo.y * wo.y);
  const float c = r > 1e-7f ? wo.x / r : 1.0f, s = r > 1e-7f ? wo.y / r : 0.0f;
  Mat3 rot(1.0f);  // rows (c, s, 0), (−s, c, 0), (0, 0, 1); glm: [column][row]
  rot[0][0] = c;
  rot[1][0] = s;
  rot[0][1] = -s;
  rot[1][1] = c;
  fit.ltc = Ltc::from_inverse(m_inv * rot);  // one inverse per lobe: this runs at every shading point
  return fit;
}

}  // namespace kozu
