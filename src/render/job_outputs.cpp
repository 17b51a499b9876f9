#include "render/job_outputs.h"

#include "core/error.h"
#include "core/json_reader.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <stdexcept>
#include <system_error>

namespace kozu::render_job {

// Frame-number patterns in output names: "%d" or "%0Nd" (printf's), e.g. out/%04d.png.
std::optional<std::pair<size_t, size_t>> find_frame_pattern(const std::string& s) {
  for (size_t i = s.find('%'); i != std::string::npos; i = s.find('%', i + 1)) {
    size_t j = i + 1;
    while (j < s.size() && std::isdigit(static_cast<unsigned char>(s[j]))) ++j;
    if (j < s.size() && s[j] == 'd' && j - i <= 4) return std::pair{i, j + 1};
  }
  return std::nullopt;
}
bool has_frame_pattern(const std::string& s) { return find_frame_pattern(s).has_value(); }
std::string frame_path(const std::string& s, int frame) {
  const auto p = find_frame_pattern(s);
  if (!p) return s;
  const std::string spec = s.substr(p->first + 1, p->second - p->first - 2);  // "04" of "%04d"
  const int width = spec.empty() ? 0 : std::stoi(spec);
  std::string number = std::to_string(frame);
  if (static_cast<int>(number.size()) < width) number.insert(0, static_cast<size_t>(width) - number.size(), '0');
  return s.substr(0, p->first) + number + s.substr(p->second);
}

// What is already under the names a numbered output takes for frames A..B: a folder, a FIFO, a device or an input of
// the render is refused, naming the frame. A pattern in the file name reads its folder once (a million frames cost
// one listing, not a million look-ups); a pattern in a folder's name looks each frame up.
void check_numbered_output(const OutputFile& o, Vec2i frames, const std::vector<std::filesystem::path>& inputs) {
  const std::string pattern = o.path.string();
  const auto p = find_frame_pattern(pattern);
  if (!p) return;
  const auto check = [&](const std::filesystem::path& path, int f) {
    std::error_code ec;
    const auto st = std::filesystem::status(path, ec);
    if (!std::filesystem::exists(st)) return;
    if (!std::filesystem::is_regular_file(st))
      throw std::runtime_error(fmt::format("{} {}: {} (frame {}); an output must be a regular file or not exist",
                                           o.flag, path.string(),
                                           std::filesystem::is_directory(st) ? "is a folder" : "is not a file", f));
    for (const auto& in : inputs)
      if (std::filesystem::equivalent(path, in, ec))
        throw std::runtime_error(fmt::format("{} {}: would overwrite {}, an input of the render (frame {})", o.flag,
                                             path.string(), in.string(), f));
  };
  const size_t slash = pattern.find_last_of('/');
  if (slash != std::string::npos && slash > p->first) {
    for (int f = frames.x; f <= frames.y; ++f) check(frame_path(pattern, f), f);
    return;
  }
  const std::string name = slash == std::string::npos ? pattern : pattern.substr(slash + 1);
  const size_t at = p->first - (slash == std::string::npos ? 0 : slash + 1);
  const std::string prefix = name.substr(0, at), suffix = name.substr(at + (p->second - p->first));
  std::filesystem::path dir = o.path.parent_path();
  if (dir.empty()) dir = ".";
  std::error_code ec;
  for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string entry = it->path().filename().string();
    if (entry.size() <= prefix.size() + suffix.size() || entry.compare(0, prefix.size(), prefix) != 0 ||
        entry.compare(entry.size() - suffix.size(), suffix.size(), suffix) != 0)
      continue;
    const std::string digits = entry.substr(prefix.size(), entry.size() - prefix.size() - suffix.size());
    if (digits.size() > 9 || !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
      continue;
    const int f = std::stoi(digits);
    if (f >= frames.x && f <= frames.y && std::filesystem::path(frame_path(pattern, f)).filename() == entry)
      check(it->path(), f);
  }
}

// "--frames A:B" (both included) or "--frames N" of an animation of `count` frames.
Vec2i frames_flag(const std::string& text, int count) {
  const auto fail = [&] {
    throw InputError("kozu render", "--frames",
                     fmt::format("expected A:B (frames A to B, both included) or N with 0 <= A <= B <= {} (the scene's "
                                 "animation has {} frames), got '{}'",
                                 count - 1, count, text_excerpt(text)));
  };
  const size_t colon = text.find(':');
  Vec2i r;
  try {
    const auto number = [&](const std::string& t) {
      return static_cast<int>(
          json_to_integer(flag_value(t), "--frames", JsonSource{"kozu render"}, Range::closed(0, count - 1)));
    };
    r.x = number(text.substr(0, colon));
    r.y = colon == std::string::npos ? r.x : number(text.substr(colon + 1));
  } catch (const InputError&) {
    fail();
  }
  if (r.x > r.y) fail();
  return r;
}

}  // namespace kozu::render_job
