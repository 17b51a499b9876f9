// The render settings that a scene's "render" block (and camera resolution) and the flags of `kozu render`
// share, each with one rule: the same type, range and message whether it comes from the file or the command
// line ("scene.json: /render/max_depth: expected an integer in [0, 1024], got 2000" and
// "kozu render: --max-depth: expected an integer in [0, 1024], got 2000").
#pragma once

#include "core/json_reader.h"
#include "core/math.h"
#include "scene/scene.h"

#include <optional>
#include <string_view>

namespace kozu {

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
inline const SettingRule kResolution{"resolution", "--resolution", Range::closed(1, 65536)};
// Flags without a scene key.
inline const SettingRule kThreads{"", "--threads", Range::closed(0, kMaxInt)};
inline const SettingRule kExposure{"", "--exposure", Range::closed(-64, 64)};
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

}  // namespace kozu
