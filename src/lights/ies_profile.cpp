#include "lights/ies_profile.h"

#include "core/error.h"
#include "core/file_io.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace kozu {

namespace {

// The numbers after the TILT line, read one at a time; blanks, tabs, commas and line ends separate them.
class NumberReader {
 public:
  NumberReader(std::string_view text, const std::string& name) : text_(text), name_(name) {}
  // The next number, or false at the end of the text; a token that is no finite number is an error naming what.
  bool next(double* value, const std::string& what) {
    while (pos_ < text_.size() && is_separator(text_[pos_])) ++pos_;
    if (pos_ >= text_.size()) return false;
    size_t end = pos_;
    while (end < text_.size() && !is_separator(text_[end])) ++end;
    const std::string token(text_.substr(pos_, end - pos_));
    pos_ = end;
    char* stop = nullptr;
    const double v = std::strtod(token.c_str(), &stop);
    if (stop != token.c_str() + token.size() || !std::isfinite(v))
      throw std::runtime_error(
          fmt::format("{}: {}: expected a finite number, got '{}'", name_, what, token.substr(0, 40)));
    *value = v;
    return true;
  }
  // Bytes of text not yet read.
  uint64_t remaining() const { return text_.size() - std::min(pos_, text_.size()); }
  double require(const std::string& what) {
    double v = 0;
    if (!next(&v, what)) throw std::runtime_error(fmt::format("{}: the file ends before the {}", name_, what));
    return v;
  }

 private:
  static bool is_separator(char c) { return c == ' ' || c == '\t' || c == ',' || c == '\r' || c == '\n'; }
  std::string_view text_;
  const std::string& name_;
  size_t pos_ = 0;
};

// Index i with a[i] <= x <= a[i + 1] (a strictly increasing, at least 2 values, x within their range).
size_t interval(const std::vector<double>& a, double x) {
  const auto it = std::upper_bound(a.begin(), a.end(), x);
  const size_t i = it == a.begin() ? 0 : size_t(it - a.begin()) - 1;
  return std::min(i, a.size() - 2);
}

}  // namespace

IesProfile IesProfile::parse(std::string_view text, const std::string& name) {
  const auto fail = [&](const std::string& message) { throw std::runtime_error(name + ": " + message); };
  // Header lines up to TILT=.
  size_t pos = 0;
  int line = 0;
  std::string tilt;
  while (pos < text.size()) {
    const size_t eol = std::min(text.find('\n', pos), text.size());
    std::string_view l = text.substr(pos, eol - pos);
    pos = eol + 1;
    ++line;
    while (!l.empty() && (l.front() == ' ' || l.front() == '\t')) l.remove_prefix(1);
    if (l.substr(0, 5) == "TILT=") {
      tilt = std::string(l.substr(5));
      while (!tilt.empty() && (tilt.back() == '\r' || tilt.back() == ' ' || tilt.back() == '\t')) tilt.pop_back();
      break;
    }
    if (pos >= text.size()) fail("no 'TILT=' line: not an IES LM-63 file");
  }
  if (text.empty()) fail("the file is empty: not an IES LM-63 file");
  if (tilt != "NONE")
    fail(fmt::format("line {}: TILT={} is not supported (lamp-tilt factors are not modelled): kozu reads TILT=NONE",
                     line, tilt.substr(0, 40)));
  NumberReader in(text.substr(std::min(pos, text.size())), name);
  const auto count = [&](const char* what) {
    const double v = in.require(what);
    if (v != std::floor(v) || v < 1 || v > kMaxAngles)
      fail(fmt::format("the {} is {:g}; expected an integer in [1, {}]", what, v, kMaxAngles));
    return size_t(v);
  };
  in.require("number of lamps");
  in.require("lumens per lamp");
  const double multiplier = in.require("candela multiplier");
  const size_t nv = count("number of vertical angles");
  const size_t nh = count("number of horizontal angles");
  const double type = in.require("photometric type");
  if (type != 1.0)
    fail(fmt::format("photometric type {:g} ({}) is not supported: kozu reads type C (1)", type,
                     type == 2.0   ? "type B"
                     : type == 3.0 ? "type A"
                                   : "unknown"));
  for (const char* what :
       {"units type", "width", "length", "height", "ballast factor", "ballast-lamp factor", "input watts"})
    in.require(what);
  if (!(multiplier > 0.0)) fail(fmt::format("the candela multiplier is {:g}; expected a number > 0", multiplier));

  // Each value still to come needs at least 2 bytes of text (a digit and a separator; the last one may lack its
  // separator), so the counts the header promises are checked against what is left of the file before anything
  // is allocated: a 200-byte header promising 10^8 values would otherwise allocate 800 MB before failing.
  const uint64_t promised = uint64_t(nv) + uint64_t(nh) + uint64_t(nv) * uint64_t(nh);
  const uint64_t left = in.remaining();
  if (promised > left / 2 + 1)
    fail(
        fmt::format("the header promises {} vertical and {} horizontal angles and {} candela values, but only {} "
                    "bytes follow (each value needs at least 2): truncated or corrupt",
                    nv, nh, uint64_t(nv) * uint64_t(nh), left));
  IesProfile p;
  p.vertical_.resize(nv);
  p.horizontal_.resize(nh);
  for (size_t i = 0; i < nv; ++i) p.vertical_[i] = in.require(fmt::format("vertical angle {}", i + 1));
  for (size_t i = 0; i < nh; ++i) p.horizontal_[i] = in.require(fmt::format("horizontal angle {}", i + 1));
  const auto check_increasing = [&](const std::vector<double>& a, const char* what) {
    for (size_t i = 1; i < a.size(); ++i)
      if (!(a[i] > a[i - 1]))
        fail(fmt::format("{} angles must be strictly increasing: angle {} is {:g} after {:g}", what, i + 1, a[i],
                         a[i - 1]));
  };
  check_increasing(p.vertical_, "vertical");
  check_increasing(p.horizontal_, "horizontal");
  if (p.vertical_.front() < 0.0 || p.vertical_.back() > 180.0)
    fail(
        fmt::format("vertical angles must lie in [0, 180], got {:g} to {:g}", p.vertical_.front(), p.vertical_.back()));
  const double last = p.horizontal_.back();
  if (p.horizontal_.front() != 0.0 || !(last == 0.0 || last == 90.0 || last == 180.0 || last == 360.0))
    fail(
        fmt::format("horizontal angles {:g} to {:g}: kozu reads type C tables from 0 to 0 (rotationally symmetric), "
                    "90 (quadrant), 180 (bilateral) or 360 (full)",
                    p.horizontal_.front(), last));

  const size_t n = nv * nh;
  p.candela_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    double v = 0;
    if (!in.next(&v, fmt::format("candela value {}", i + 1)))
      fail(fmt::format("expected {} candela values ({} horizontal x {} vertical angles), found {}", n, nh, nv, i));
    if (v < 0.0) fail(fmt::format("candela value {} is {:g}; candela values must be >= 0", i + 1, v));
    p.candela_[i] = v * multiplier;
  }
  double extra = 0;
  if (in.next(&extra, "value after the candela values"))
    fail(fmt::format("expected {} candela values ({} horizontal x {} vertical angles), found more", n, nh, nv));
  p.peak_ = *std::max_element(p.candela_.begin(), p.candela_.end());
  if (!(p.peak_ > 0.0)) fail("every candela value is 0: the luminaire emits nothing");
  if (!std::isfinite(p.peak_)) fail("the candela values times the multiplier overflow");
  for (double& v : p.candela_) v /= p.peak_;
  return p;
}

IesProfile IesProfile::load(const std::filesystem::path& file) {
  std::string text;
  try {
    text = read_input_file(file, kMaxFileBytes);
  } catch (const InputError& e) {
    throw std::runtime_error(e.what());
  }
  return parse(text, file.string());
}

double IesProfile::fold(double c) const {
  c = std::fmod(c, 360.0);
  if (c < 0.0) c += 360.0;
  const double last = horizontal_.back();
  if (last == 360.0) return c;
  if (c > 180.0) c = 360.0 - c;                 // bilateral and quadrant: mirror about the C = 0-180 plane
  if (last == 90.0 && c > 90.0) c = 180.0 - c;  // quadrant: and about the C = 90-270 plane
  return c;
}

double IesProfile::column(size_t h, double theta) const {
  const double* col = &candela_[h * vertical_.size()];
  if (theta < vertical_.front() || theta > vertical_.back()) return 0.0;
  if (vertical_.size() == 1) return col[0];
  const size_t i = interval(vertical_, theta);
  const double t = (theta - vertical_[i]) / (vertical_[i + 1] - vertical_[i]);
  return col[i] + t * (col[i + 1] - col[i]);
}

float IesProfile::eval_angles(double theta, double c) const {
  if (horizontal_.size() == 1) return float(column(0, theta));
  c = fold(c);
  const size_t j = interval(horizontal_, c);
  const double t = std::clamp((c - horizontal_[j]) / (horizontal_[j + 1] - horizontal_[j]), 0.0, 1.0);
  return float((1.0 - t) * column(j, theta) + t * column(j + 1, theta));
}

float IesProfile::eval(const Vec3& w) const {
  const double theta = glm::degrees(std::acos(std::clamp(double(w.z), -1.0, 1.0)));
  const double c = (w.x == 0.0f && w.y == 0.0f) ? 0.0 : glm::degrees(std::atan2(double(w.y), double(w.x)));
  return eval_angles(theta, c);
}

double IesProfile::integral(const std::function<double(double)>& weight, const std::vector<double>& breaks) const {
  // mean over C of the bilinear interpolation at theta: the trapezoid rule over the table's C nodes is exact for it,
  // and each symmetry repeats the table's range to fill 360 degrees.
  const auto mean_c = [&](double theta) {
    const size_t nh = horizontal_.size();
    if (nh == 1) return column(0, theta);
    double sum = 0.0;
    for (size_t j = 0; j + 1 < nh; ++j)
      sum += 0.5 * (column(j, theta) + column(j + 1, theta)) * (horizontal_[j + 1] - horizontal_[j]);
    return sum / horizontal_.back();
  };
  std::vector<double> cuts = vertical_;
  cuts.push_back(0.0);
  cuts.push_back(180.0);
  for (double b : breaks)
    if (b > 0.0 && b < 180.0) cuts.push_back(b);
  std::sort(cuts.begin(), cuts.end());
  // 8-point Gauss-Legendre on pieces of at most 5 degrees, between consecutive cuts.
  static constexpr double kX[8] = {-0.9602898564975363, -0.7966664774136267, -0.5255324099163290, -0.1834346424956498,
                                   0.1834346424956498,  0.5255324099163290,  0.7966664774136267,  0.9602898564975363};
  static constexpr double kW[8] = {0.1012285362903763, 0.2223810344533745, 0.3137066458778873, 0.3626837833783620,
                                   0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};
  double sum = 0.0;
  for (size_t k = 0; k + 1 < cuts.size(); ++k) {
    const double a = cuts[k], b = cuts[k + 1];
    if (!(b > a)) continue;
    const int pieces = int(std::ceil((b - a) / 5.0));
    for (int p = 0; p < pieces; ++p) {
      const double lo = a + (b - a) * p / pieces, hi = a + (b - a) * (p + 1) / pieces;
      // Sample strictly inside the piece: the profile is continuous there (0 beyond the vertical range).
      for (int i = 0; i < 8; ++i) {
        const double theta = 0.5 * (lo + hi) + 0.5 * (hi - lo) * kX[i];
        const double cos_t = std::cos(glm::radians(theta));
        const double f = mean_c(theta) * (weight ? weight(cos_t) : 1.0);
        sum += kW[i] * 0.5 * glm::radians(hi - lo) * f * std::sin(glm::radians(theta));
      }
    }
  }
  return 2.0 * M_PI * sum;
}

Frame luminaire_frame(const Vec3& nadir) {
  const Vec3 n = glm::normalize(nadir);
  Vec3 ref(1.0f, 0.0f, 0.0f);
  if (std::abs(n.x) > 0.9998f) ref = Vec3(0.0f, 0.0f, 1.0f);
  const Vec3 s = glm::normalize(ref - n * glm::dot(ref, n));
  return Frame(s, glm::cross(s, n), n);
}

std::shared_ptr<const IesProfile> IesProfile::load_for(const JsonObject& light, const std::filesystem::path& file) {
  try {
    return std::make_shared<const IesProfile>(load(file));
  } catch (const std::runtime_error& e) {
    light.fail("profile", e.what());
  }
}

}  // namespace kozu
