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
  s.volume_mis = r.get_enum("volume_sampling", {"mis", "distance"}, std::string("mis")) == "mis";
  s.light_tree = r.get_enum("light_selection", {"tree", "power"}, std::string("tree")) == "tree";
  s.lobe_light_sampling = r.get_enum("light_sampling", {"lobe", "light"}, std::string("lobe")) == "lobe";
  s.guiding = r.get_enum("guiding", {"off", "on"}, std::string("off")) == "on";
  // "ltc" by default: it is "sample" where no polygon light can take its control variate, and skips it where the
  // pixels around found it does not pay (docs/lights.md). Not under guiding, which guides "sample"'s paths alone.
  s.direct =
      parse_direct_lighting(r.get_enum("direct", direct_lighting_names(), std::string(s.guiding ? "sample" : "ltc")));
  s.keep_negative = r.get_enum("negative_pixels", {"clamp", "keep"}, std::string("clamp")) == "keep";
  s.emission_supersampling = r.get_enum("emission_supersampling", {"on", "off"}, std::string("on")) == "on";
  if (r.has(setting::kClamp.key))
    s.clamp = static_cast<float>(std::min(r.get_double(setting::kClamp.key, 0.0, setting::kClamp.range), 3e38));
  s.noise_threshold = static_cast<float>(
      std::min(r.get_double(setting::kNoiseThreshold.key, 0.0, setting::kNoiseThreshold.range), 1e30));
  s.min_spp = r.get_int(setting::kMinSpp.key, 64, setting::kMinSpp.range);
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

Vec2i sample_range_flag(std::string_view text) {
  const auto fail = [&] {
    throw InputError(command_line().display_name, "--sample-range",
                     fmt::format("expected A:B with integers 0 <= A < B <= {} (samples A .. B-1 of every pixel), "
                                 "got '{}'",
                                 static_cast<int64_t>(setting::kMaxInt), text_excerpt(text)));
  };
  const size_t colon = text.find(':');
  if (colon == std::string_view::npos) fail();
  int64_t a = 0, b = 0;
  try {
    a = json_to_integer(flag_value(text.substr(0, colon)), "--sample-range", command_line(),
                        Range::closed(0, setting::kMaxInt));
    b = json_to_integer(flag_value(text.substr(colon + 1)), "--sample-range", command_line(),
                        Range::closed(0, setting::kMaxInt));
  } catch (const InputError&) {
    fail();
  }
  if (a >= b) fail();
  return {static_cast<int>(a), static_cast<int>(b)};
}

PixelWindow crop_flag(std::string_view text, Vec2i res) {
  const auto fail = [&](const std::string& why) {
    throw InputError(command_line().display_name, "--crop",
                     fmt::format("expected X0,Y0,X1,Y1 with 0 <= X0 < X1 <= {} and 0 <= Y0 < Y1 <= {} (pixels X0 .. "
                                 "X1-1 by Y0 .. Y1-1 of the {}x{} image){}, got '{}'",
                                 res.x, res.y, res.x, res.y, why, text_excerpt(text)));
  };
  int64_t v[4];
  std::string_view rest = text;
  for (int i = 0; i < 4; ++i) {
    const size_t comma = rest.find(',');
    if ((i < 3) != (comma != std::string_view::npos)) fail("");
    const std::string_view item = i < 3 ? rest.substr(0, comma) : rest;
    try {
      v[i] = json_to_integer(flag_value(item), "--crop", command_line(), Range::closed(0, 65536));
    } catch (const InputError&) {
      fail("");
    }
    if (i < 3) rest = rest.substr(comma + 1);
  }
  if (!(v[0] < v[2] && v[1] < v[3] && v[2] <= res.x && v[3] <= res.y)) fail("");
  return {{static_cast<int>(v[0]), static_cast<int>(v[1])},
          {static_cast<int>(v[2] - v[0]), static_cast<int>(v[3] - v[1])}};
}

}  // namespace kozu
