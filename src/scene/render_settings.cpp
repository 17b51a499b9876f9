#include "scene/render_settings.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <utility>
#include <vector>

namespace kozu {

namespace {

const JsonSource& command_line() {
  static const JsonSource source{"kozu render", "."};
  return source;
}

std::string flag_path(const SettingRule& rule) { return std::string(rule.flag); }

// The one list of "direct" values: the parser, the scene key's choices and the names in --stats read it.
constexpr std::pair<DirectLighting, const char*> kDirectNames[] = {{DirectLighting::Sample, "sample"},
                                                                   {DirectLighting::Ltc, "ltc"},
                                                                   {DirectLighting::LtcRatio, "ltc-ratio"},
                                                                   {DirectLighting::LtcPreview, "ltc-preview"}};

std::vector<std::string> direct_lighting_names() {
  std::vector<std::string> names;
  for (const auto& [d, name] : kDirectNames) names.emplace_back(name);
  return names;
}

}  // namespace

DirectLighting parse_direct_lighting(std::string_view name) {
  for (const auto& [d, n] : kDirectNames)
    if (name == n) return d;
  throw std::invalid_argument(
      fmt::format("expected one of {}, got '{}'", fmt::join(direct_lighting_names(), ", "), text_excerpt(name)));
}

const char* direct_lighting_name(DirectLighting d) {
  for (const auto& [value, name] : kDirectNames)
    if (value == d) return name;
  return "sample";
}

std::optional<std::string> sample_limit_problem(const RenderSettings& s) {
  if (s.spp == 0 && !(s.time_limit > 0.0)) return "spp 0 (no sample limit) needs a time limit > 0";
  return std::nullopt;
}

RenderSettings parse_render_settings(const JsonObject& r) {
  RenderSettings s;
  s.spp = r.get_int(setting::kSpp.key, 64, setting::kSpp.range);
  s.max_depth = r.get_int(setting::kMaxDepth.key, 16, setting::kMaxDepth.range);
  s.seed = r.get_uint64("seed", 0);
  s.time_limit = r.get_double(setting::kTimeLimit.key, 0.0, setting::kTimeLimit.range);
  s.filter = PixelFilter::parse(r.get_enum("filter", {"box", "tent", "gaussian"}, std::string("gaussian")));
  s.direct = parse_direct_lighting(r.get_enum("direct", direct_lighting_names(), std::string("sample")));
  if (const auto problem = sample_limit_problem(s)) r.fail("spp", *problem);
  r.finish();
  return s;
}

Vec2i parse_resolution(const JsonObject& camera) {
  const JsonArray r = camera.get_array(setting::kResolution.key);
  if (r.size() != 2) r.fail("expected [width, height]");
  return Vec2i(static_cast<int>(r.integer(0, setting::kResolution.range)),
               static_cast<int>(r.integer(1, setting::kResolution.range)));
}

int64_t integer_flag(std::string_view text, const SettingRule& rule) {
  return json_to_integer(flag_value(text), flag_path(rule), command_line(), rule.range);
}

double number_flag(std::string_view text, const SettingRule& rule) {
  return json_to_double(flag_value(text), flag_path(rule), command_line(), rule.range);
}

uint64_t seed_flag(std::string_view text) { return json_to_uint64(flag_value(text), "--seed", command_line()); }

Vec2i resolution_flag(std::string_view text) {
  const Range& range = setting::kResolution.range;
  const auto fail = [&] {
    throw InputError(command_line().display_name, flag_path(setting::kResolution),
                     fmt::format("expected WIDTHxHEIGHT with each an integer {} (e.g. 1920x1080), got '{}'",
                                 range.describe(), text_excerpt(text)));
  };
  const size_t x = text.find_first_of("xX");
  if (x == std::string_view::npos) fail();
  const Json w = flag_value(text.substr(0, x)), h = flag_value(text.substr(x + 1));
  // The integer rule of the scene key: integral values in range.
  const auto valid = [&](const Json& v) {
    return v.is_number() && v.get<double>() == std::floor(v.get<double>()) && range.contains(v.get<double>());
  };
  if (!valid(w) || !valid(h)) fail();
  return Vec2i(static_cast<int>(w.get<double>()), static_cast<int>(h.get<double>()));
}

}  // namespace kozu
