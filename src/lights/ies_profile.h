// ies_profile: a luminaire's photometric intensity distribution read from an IES LM-63 file (IES LM-63-1995,
// LM-63-2002: "IES Standard File Format for the Electronic Transfer of Photometric Data"), the goniometric profile
// of kozu's point and spot lights ("profile", docs/lights.md "IES profiles"). No seed file covers it.
//
// The subset read:
//   - any header lines (IESNA:LM-63-..., [KEYWORD] lines) up to the line that starts with "TILT=";
//   - TILT=NONE only (TILT=INCLUDE and TILT=<file> are refused: lamp-tilt factors are not modelled);
//   - then numbers separated by blanks, commas or line ends: number of lamps, lumens per lamp, candela multiplier,
//     number of vertical angles V, number of horizontal angles H, photometric type (1 = type C only; types A (3)
//     and B (2) are refused), units type, width, length, height, ballast factor, future use (ballast-lamp factor),
//     input watts, V vertical angles, H horizontal angles, H x V candela values (for each horizontal angle, its
//     vertical column).
// Checks: the file is at most kMaxFileBytes (before reading it); V and H in [1, kMaxAngles] (before allocating);
// every number finite; vertical angles strictly increasing within [0, 180]; horizontal angles strictly increasing,
// starting at 0 and ending at 0 (one angle: rotationally symmetric), 90 (quadrant symmetry: the data of C in [0, 90]
// mirrored into the other three quadrants), 180 (bilateral: mirrored about the C = 0-180 plane) or 360 (full);
// candela values finite and >= 0, not all 0; exactly H x V of them ("expected N candela values, found M").
//
// Conventions (type C): the vertical angle theta is measured from the photometric nadir (theta = 0 straight down
// out of the luminaire, 180 straight up); the horizontal angle C turns about the nadir axis, counter-clockwise seen
// from above (looking along the nadir), from C = 0 towards C = 90. Outside the vertical angles' range the intensity
// is 0 (a table of 0..90 emits nothing upwards). Between table angles the candela values are interpolated bilinearly
// in (theta, C); the profile is normalised so that its largest table value is 1, the light's intensity scaling it.
// The candela multiplier, lumens and watts are not used: the light's "intensity" or "power" sets the scale.
#pragma once

#include "core/frame.h"
#include "core/json_reader.h"
#include "core/math.h"

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace kozu {

class IesProfile {
 public:
  static constexpr uint64_t kMaxFileBytes = uint64_t{16} << 20;  // 16 MiB: real files are a few kB
  static constexpr int kMaxAngles = 10000;

  // Parses the text of an IES file; errors (std::runtime_error) start with name, the file's name.
  static IesProfile parse(std::string_view text, const std::string& name);
  // Reads and parses a file: the size is checked before it is read.
  static IesProfile load(const std::filesystem::path& file);
  // load() for the light `light`: a bad file fails at its "profile" key.
  static std::shared_ptr<const IesProfile> load_for(const JsonObject& light, const std::filesystem::path& file);

  // The normalised intensity (largest table value 1) towards the direction (theta from the nadir, C), in degrees.
  float eval_angles(double theta_deg, double c_deg) const;
  // The same for a unit direction in the luminaire frame: z is the nadir, x is C = 0, y is C = 90.
  float eval(const Vec3& local) const;
  // The integral over the sphere of the normalised profile times weight(cos theta) (theta from the nadir):
  // 2 pi int mean_C(theta) weight(cos theta) sin theta d theta, with mean_C exact for the bilinear interpolation and
  // Gauss-Legendre quadrature in theta on intervals split at the table's angles and at the extra break points
  // (degrees; the kinks of weight). weight null: 1.
  double integral(const std::function<double(double)>& weight = {}, const std::vector<double>& breaks = {}) const;

  const std::vector<double>& vertical() const { return vertical_; }
  const std::vector<double>& horizontal() const { return horizontal_; }
  // The candela values as read (times the file's multiplier), column h (horizontal angle h) row v.
  double candela(size_t h, size_t v) const { return candela_[h * vertical_.size() + v] * peak_; }
  double peak_candela() const { return peak_; }

 private:
  // The C angle folded into the table's range by its symmetry.
  double fold(double c_deg) const;
  // Column h linearly interpolated at theta (0 outside the vertical range).
  double column(size_t h, double theta_deg) const;

  std::vector<double> vertical_, horizontal_;
  std::vector<double> candela_;  // normalised, H columns of V values
  double peak_ = 1.0;
};

// The frame of a luminaire whose nadir is the unit vector nadir: n = nadir; s (C = 0) along world +x projected onto
// the plane across the nadir (along +z when the nadir is within about 1 degree of the x axis); t (C = 90) = s x nadir,
// so that C grows counter-clockwise seen from above (from -nadir). With the default nadir [0, -1, 0]: C = 0 is +x,
// C = 90 is -z.
Frame luminaire_frame(const Vec3& nadir);

}  // namespace kozu
