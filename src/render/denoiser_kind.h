// The filters of `--denoise` (`--denoiser NAME`, kozu.render(denoiser=...)): their names and the choice.
#pragma once

#include <optional>
#include <string_view>

namespace kozu {

enum class DenoiserKind {
  NlMeans,     // feature-guided non-local means (render/denoiser.h), the default
  Regression,  // first-order feature regression (render/feature_regression.h)
  Unet,        // the learned U-Net (render/learned_denoiser.h)
  Ensemble,    // NL-means and the regression, weighed by their estimated errors (render/denoiser_ensemble.h)
};

inline constexpr const char* kDenoiserNames = "nlmeans (the default), regression, unet or ensemble";

inline std::optional<DenoiserKind> parse_denoiser_kind(std::string_view name) {
  if (name == "nlmeans") return DenoiserKind::NlMeans;
  if (name == "regression") return DenoiserKind::Regression;
  if (name == "unet") return DenoiserKind::Unet;
  if (name == "ensemble") return DenoiserKind::Ensemble;
  return std::nullopt;
}

}  // namespace kozu
