// The render settings: one struct that a scene's "render" block fills, `kozu render`'s flags override, and the
// renderer (render/renderer.h) takes. The scene keys and the flags share each rule: the same type, range and message
// whether it comes from the file or the command line ("scene.json: /render/max_depth: expected an integer in [0, 1024],
// got 2000" and "kozu render: --max-depth: expected an integer in [0, 1024], got 2000").
#pragma once

#include "core/json_reader.h"
#include "core/math.h"
#include "scene/filter.h"

#include <optional>
#include <string>
#include <string_view>

namespace kozu {

// How surface vertices take direct light from polygon lights (integrators/path.h, docs/lights.md).
enum class DirectLighting {
  Sample,      // light and BSDF sampling under MIS, as for every light
  Ltc,         // the LTC integral plus a Monte Carlo estimate of its error, shadows included: unbiased
  LtcPreview,  // the LTC integral alone: no shadows from polygon lights, biased, noiseless (Heitz et al. 2016's
               // real-time use)
  LtcRatio,    // the LTC integral times shadowed / unshadowed estimates (Heitz, Hill, McGuire 2018): consistent, biased
};
DirectLighting parse_direct_lighting(std::string_view name);  // "sample", "ltc", "ltc-ratio", "ltc-preview"; throws
const char* direct_lighting_name(DirectLighting d);

struct RenderSettings {
  int spp = 64;        // samples per pixel; 0 = until the time limit (needs one: sample_limit_problem)
  int max_depth = 16;  // maximum number of scattering events on a path
  uint64_t seed = 0;
  double time_limit = 0.0;  // seconds of sampling (loading excluded), 0 = none; above kMaxTimeLimit counts as it
  PixelFilter::Type filter = PixelFilter::Type::Gaussian;
  DirectLighting direct = DirectLighting::Ltc;  // "sample" under guiding (parse_render_settings)
  // "volume_sampling": in homogeneous media, direct light scattered along a ray by free flights and equiangular
  // sampling towards the light under MIS ("mis", the default), or by free flights alone ("distance").
  bool volume_mis = true;
  // "light_selection": the light of each next-event estimate chosen by the light hierarchy, by its estimated
  // contribution at the point ("tree", the default: lights/light_tree.h), or in proportion to power alone ("power").
  bool light_tree = true;
  // "light_sampling": with "direct": "sample", how a surface vertex with a glossy lobe samples a flat area light:
  // partly from the lobe restricted to the light ("lobe", the default: integrators/lobe_light_sampler.h), or from the
  // light alone ("light").
  bool lobe_light_sampling = true;
  // "guiding": practical path guiding (Müller, Gross, Novák 2017; integrators/guiding_field.h), trained in passes
  // before each frame's samples (render/guiding_training.h): "on", or "off" (the default).
  bool guiding = false;
  // "emission_supersampling": the visible emission of the pixels where it varies (emitters' edges, their
  // reflections in mirrors) estimated apart with many cheap camera rays before the render
  // (render/emission_supersampling.h): "on" (the default) or "off". Unused with the denoiser's features, with
  // checkpoints and below 16 samples a pixel (spp 0 included).
  bool emission_supersampling = true;
  // Fireflies: each sample's RGB is scaled so that its largest component is at most this (pbrt-v4's film
  // "maxcomponentvalue"); 0 = off (the default). Biased: it darkens what only rare paths carry.
  float clamp = 0.0f;
  // "negative_pixels": "clamp" (the default) writes a pixel whose mean is below 0 (the control variate of "direct":
  // "ltc" may give one at a few samples a pixel: docs/lights.md) as 0 in the images; "keep" writes the signed,
  // unbiased mean. A --sample-range part keeps it whatever this says, so that its merge is the whole render's.
  bool keep_negative = false;
  // Adaptive sampling (render/adaptive_sampling.h): between passes, a pixel with at least min_spp samples whose
  // error estimate (the standard error of its luminance mean over the square root of max(luminance, 0.01)), and its
  // neighbours', is at most noise_threshold takes no more samples. 0 = off (the default).
  float noise_threshold = 0.0f;
  int min_spp = 64;
  // Not scene keys: flags of `kozu render`, or fixed.
  int threads = 0;  // 0 = all hardware threads; at most max_render_threads() (render/renderer.h)
  int tile_size = 16;
  // Samples per pass after the first, 0 = the growing schedule of renderer.cpp. Not a user setting: it lets
  // tests render the same samples under other pass schedules, which must give the same image.
  int pass_samples = 0;
  // The first sample index of every pixel (`--sample-range a:b`: samples a .. b-1, with spp = b), so that renders
  // of disjoint ranges add up to one render of their union.
  int sample_begin = 0;
  // This process renders tiles i with i mod tile_ranks == tile_rank (MPI ranks: apps/mpi_world.h).
  int tile_rank = 0, tile_ranks = 1;

  static constexpr double kMaxTimeLimit = 1e9;  // about 32 years: a clock cannot overflow below it
};

// The one rule between settings: without a sample cap (spp 0) a render needs a time limit. Returns the message
// when s breaks it, whether s came from the file or from the flags.
std::optional<std::string> sample_limit_problem(const RenderSettings& s);

struct SettingRule {
  std::string_view key;   // scene key (in "render", or the camera's "resolution")
  std::string_view flag;  // `kozu render` flag
  Range range;
};

namespace setting {
inline constexpr double kMaxInt = 2147483647.0;
inline const SettingRule kSpp{"spp", "--spp", Range::closed(0, kMaxInt)};
inline const SettingRule kMaxDepth{"max_depth", "--max-depth", Range::closed(0, 1024)};
// Seconds; values beyond kMaxTimeLimit mean "no practical limit" (the renderer saturates them).
inline const SettingRule kTimeLimit{"time_limit", "--time-limit", Range::non_negative()};
inline const SettingRule kClamp{"clamp", "", Range::positive()};
inline const SettingRule kNoiseThreshold{"noise_threshold", "", Range::non_negative()};
inline const SettingRule kMinSpp{"min_spp", "", Range::closed(2, kMaxInt)};
inline const SettingRule kResolution{"resolution", "--resolution", Range::closed(1, 65536)};
// Flags without a scene key.
inline const SettingRule kThreads{"", "--threads", Range::closed(0, kMaxInt)};
inline const SettingRule kExposure{"", "--exposure", Range::closed(-64, 64)};
inline const SettingRule kTextureCacheMb{"", "--texture-cache-mb", Range::closed(16, 1048576)};
// Production flags (docs/production.md), in seconds.
inline const SettingRule kBudget{"", "--budget", Range{0.0, 1e9, true, false}};
inline const SettingRule kPartialEvery{"", "--partial-every", Range{0.0, 1e9, true, false}};
inline const SettingRule kCheckpointEvery{"", "--checkpoint-every", Range{0.0, 1e9, true, false}};
}  // namespace setting

// Reads the scene's "render" block.
RenderSettings parse_render_settings(const JsonObject& render);
// Reads a camera "resolution" array [width, height].
Vec2i parse_resolution(const JsonObject& camera);

// Flags, validated by the rule of their scene key; errors are InputError("kozu render", FLAG, message).
int64_t integer_flag(std::string_view text, const SettingRule& rule);
double number_flag(std::string_view text, const SettingRule& rule);
uint64_t seed_flag(std::string_view text);
// "WIDTHxHEIGHT".
Vec2i resolution_flag(std::string_view text);
// "--sample-range A:B": samples A .. B-1 of every pixel, 0 <= A < B <= 2^31 - 1.
Vec2i sample_range_flag(std::string_view text);
// "--crop X0,Y0,X1,Y1": pixels X0 .. X1-1 by Y0 .. Y1-1 of a resolution-sized image.
struct PixelWindow {
  Vec2i origin{0}, size{0};
};
PixelWindow crop_flag(std::string_view text, Vec2i resolution);

}  // namespace kozu
