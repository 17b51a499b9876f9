#include "render/job_budget.h"

#include "core/file_io.h"
#include "core/rng.h"
#include "core/temp_files.h"
#include "io/image_io.h"
#include "render/denoiser.h"
#include "render/denoiser_ensemble.h"
#include "render/feature_regression.h"
#include "render/film.h"
#include "render/learned_denoiser.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <map>

namespace kozu::render_job {

// What finishing an image output costs here and now, in seconds for `pixels`: two films of 160 x 90 and 320 x 180
// with most pixels unsampled turned into images (the hole filling a render stopped early needs) and written in the
// output's format into its folder, timed; their difference is the cost per pixel (at least the floor measured on
// a quiet 2-core machine, docs/production.md), the rest the fixed cost of a write. A loaded machine, a sanitizer
// build or a slow disk shows in them. `slowdown` is the measured cost per pixel over the floor's.
double write_seconds(const OutputFile& o, const ToneMap& tonemap, double pixels, int extra_channels, double* slowdown) {
  const std::string ext = lower_extension(o.path);
  // Uncompressed EXR about 41 ns per pixel at 3840 x 2160 (with the film's conversion), zipped 270; PNG 185-250.
  const double floor = ext == ".exr" ? 60e-9 : ext == ".hdr" ? 270e-9 : 250e-9;
  std::filesystem::path probe = o.path;
  probe.replace_filename(fmt::format(".kozu-calibrate.{}{}", getpid(), ext));
  TempFileGuard guard(probe);  // removed on every exit path
  double t[2] = {0.0, 0.0};
  const int widths[2] = {160, 320};
  for (int k = 0; k < 2; ++k) {
    const int w = widths[k], h = w * 9 / 16;
    Film film(w, h);
    for (int y = 0; y < h; y += 8)
      for (int x = 0; x < w; x += 8) film.add_sample(x, y, Rgb(static_cast<float>((x * 7 + y * 13) % 100) * 0.01f));
    const auto start = std::chrono::steady_clock::now();
    try {
      ImageExtras extras;
      extras.exr_compression = kBudgetExrCompression;
      if (ext == ".exr")
        for (int c = 0; c < extra_channels; ++c) extras.channels.push_back(fmt::format("extra{}", c));
      extras.data.assign(extras.channels.size() * static_cast<size_t>(w) * h, 0.5f);
      write_image(probe, w, h, film.rgb(), tonemap, extras);
    } catch (const std::exception&) {
      return floor * pixels;  // the real write will report its own error
    }
    t[k] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  const double n0 = 160.0 * 90.0, n1 = 320.0 * 180.0;
  const double per_pixel = std::max(floor, (t[1] - t[0]) / (n1 - n0));
  const double fixed = std::max(0.0, t[0] - per_pixel * n0);
  *slowdown = std::max(*slowdown, per_pixel / floor);
  return fixed + per_pixel * pixels;
}

// The filter stops at its own deadline (render/denoiser.h, render/feature_regression.h): its estimate needs less
// margin than a write's, which cannot be cut short.
constexpr double kFilterMargin = 1.15;

std::vector<float> run_denoiser(DenoiserKind denoiser, const Film& film, const VisibleEmission* emission,
                                const std::function<bool()>& expired, int threads) {
  switch (denoiser) {
    case DenoiserKind::NlMeans:
      return denoise(film, {}, emission, expired);
    case DenoiserKind::Regression:
      return denoise_regression(film, {}, emission, expired);
    case DenoiserKind::Unet: {
      UnetSettings s;
      s.threads = threads;
      return denoise_learned(film, emission, expired, s);
    }
    case DenoiserKind::Ensemble:
      return denoise_ensemble(film, emission, expired);
  }
  return {};
}

double denoise_seconds(double pixels, DenoiserKind denoiser, double* slowdown) {
  // Floors per pixel on a quiet 2-core machine (docs/production.md).
  const bool unet = denoiser == DenoiserKind::Unet;
  const double floor = denoiser == DenoiserKind::NlMeans      ? 1.5e-6
                       : denoiser == DenoiserKind::Regression ? 0.8e-6
                       : denoiser == DenoiserKind::Ensemble   ? 2.3e-6
                                                              : 1e-6;
  const int w = unet ? 192 : 160, h = unet ? 96 : 90;
  Film film(w, h);
  film.enable_features();
  Pcg32 rng(7);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int s = 0; s < 4; ++s) {
        const Rgb L(rng.next_float(), rng.next_float(), rng.next_float());
        PixelFeatures f;
        f.albedo = Rgb(0.2f + 0.6f * static_cast<float>(x > w / 2));
        f.normal = glm::normalize(Vec3(rng.next_float() - 0.5f, rng.next_float() - 0.5f, 1.0f));
        f.depth = 1.0f + static_cast<float>(y) / h;
        f.set = true;
        film.add_features(x, y, f, s % 2 == 0 ? &L : nullptr);
        film.add_sample(x, y, L);
      }
  const auto start = std::chrono::steady_clock::now();
  const std::vector<float> out = run_denoiser(denoiser, film);
  if (out.size() != 3u * w * h) return floor * pixels;
  const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double per_pixel = std::max(floor, t / (static_cast<double>(w) * h));
  *slowdown = std::max(*slowdown, per_pixel / floor);
  return per_pixel * pixels;
}

// The image writes (calibrated above) and a checkpoint (56 bytes per pixel at 200 MB/s), times 1.5; the denoiser's
// filter times kFilterMargin;
// plus 0.25 s for the statistics, the exit and the scheduler, scaled by the calibration's slowdown (a machine 3 times
// slower than the floor gets 0.75 s).
FinishCost finish_seconds(Vec2i size, const std::vector<OutputFile>& outputs, const ToneMap& tonemap, bool checkpoint,
                          bool denoise, bool denoise_only, DenoiserKind denoiser, int extra_channels) {
  const double pixels = static_cast<double>(size.x) * size.y;
  double raw = 0.0, denoised_writes = 0.0, slowdown = 1.0;
  // One calibration per folder and format: outputs that share both cost the same.
  std::map<std::pair<std::filesystem::path, std::string>, double> measured;
  for (const auto& o : outputs) {
    if (!o.image) continue;
    const auto key = std::pair{o.path.parent_path(), lower_extension(o.path)};
    const auto it = measured.find(key);
    const double s =
        it != measured.end()
            ? it->second
            : measured.emplace(key, write_seconds(o, tonemap, pixels, extra_channels, &slowdown)).first->second;
    // --denoise-only writes its outputs raw first under a budget, then denoised if time allows.
    if (!o.denoised || denoise_only) raw += s;
    if (o.denoised) denoised_writes += s;
  }
  if (checkpoint) raw += 56.0 * pixels / 200e6;
  // The filter's margin is smaller than the writes': past its own deadline it degrades instead of overrunning.
  double filter = 0.0, refine = 0.0;
  if (denoise) {
    double filter_slowdown = 1.0;
    filter = denoise_seconds(pixels, denoiser, &filter_slowdown);
    refine = kEmissionRefineSecondsPerPixel * std::max(slowdown, filter_slowdown) * pixels;
    filter += refine;
    slowdown = std::max(slowdown, filter_slowdown);
  }
  return {1.5 * raw,
          1.5 * denoised_writes + kFilterMargin * filter,
          1.5 * denoised_writes,
          0.25 * std::min(slowdown, 8.0),
          filter,
          refine};
}

}  // namespace kozu::render_job
