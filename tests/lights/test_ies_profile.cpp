// IES LM-63 profiles (lights/ies_profile.h) and the point and spot lights they shape: the parsed values,
// interpolation at and between table angles, each horizontal symmetry, the normalisation, the integral the light's
// power uses, the intensity a receiver gets, and the refused files.
#include "core/error.h"
#include "core/memory.h"
#include "lights/ies_profile.h"
#include "lights/point.h"
#include "lights/spot.h"
#include "scene/scene_loader.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace kozu::test {
namespace {

// The text of a type C file (or of another photometric type or tilt).
std::string ies_text(const std::vector<double>& v, const std::vector<double>& h, const std::vector<double>& cd,
                     double multiplier = 1.0, const std::string& tilt = "NONE", int type = 1) {
  return fmt::format(
      "IESNA:LM-63-2002\n[TEST] kozu unit test\n[MANUFAC] none\nTILT={}\n1 1000 {} {} {} {} 2 0.1 0.2 0\n1.0 1.0 "
      "60\n{}\n{}\n{}\n",
      tilt, multiplier, v.size(), h.size(), type, fmt::join(v, " "), fmt::join(h, " "), fmt::join(cd, " "));
}

std::filesystem::path write_file(const std::string& name, const std::string& text) {
  const std::filesystem::path p = std::filesystem::path(::testing::TempDir()) / name;
  std::ofstream(p, std::ios::binary) << text;
  return p;
}

std::string parse_error(const std::string& text) {
  try {
    IesProfile::parse(text, "lamp.ies");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "(parsed)";
}

// A rotationally symmetric profile: 100, 80, 40, 0 cd at 0, 30, 60, 90 degrees, times 2.
const std::string kRound = ies_text({0, 30, 60, 90}, {0}, {100, 80, 40, 0}, 2.0);

TEST(IesProfile, ParsesTheValuesAndNormalisesToThePeak) {
  const IesProfile p = IesProfile::parse(kRound, "round.ies");
  EXPECT_EQ(p.vertical(), (std::vector<double>{0, 30, 60, 90}));
  EXPECT_EQ(p.horizontal(), (std::vector<double>{0}));
  EXPECT_DOUBLE_EQ(p.peak_candela(), 200.0);
  EXPECT_DOUBLE_EQ(p.candela(0, 1), 160.0);
  // At table angles: the values over the peak; between them, linear in theta; beyond 90, nothing.
  EXPECT_FLOAT_EQ(p.eval_angles(0, 0), 1.0f);
  EXPECT_FLOAT_EQ(p.eval_angles(30, 123), 0.8f);
  EXPECT_FLOAT_EQ(p.eval_angles(45, 0), 0.6f);
  EXPECT_FLOAT_EQ(p.eval_angles(50, 300), 0.8f - 0.4f * (20.0f / 30.0f));
  EXPECT_FLOAT_EQ(p.eval_angles(90, 0), 0.0f);
  EXPECT_FLOAT_EQ(p.eval_angles(120, 0), 0.0f);
}

// Columns of constant candela over theta, different per C, so that eval depends on C alone.
float at_c(const IesProfile& p, double c) { return p.eval_angles(40.0, c); }

TEST(IesProfile, QuadrantSymmetry) {
  const IesProfile p = IesProfile::parse(ies_text({0, 90}, {0, 45, 90}, {10, 10, 20, 20, 40, 40}), "q.ies");
  EXPECT_FLOAT_EQ(at_c(p, 0), 0.25f);
  EXPECT_FLOAT_EQ(at_c(p, 45), 0.5f);
  EXPECT_FLOAT_EQ(at_c(p, 90), 1.0f);
  EXPECT_FLOAT_EQ(at_c(p, 22.5), 0.375f);
  for (const double c : {157.5, 202.5, 337.5, -22.5}) EXPECT_FLOAT_EQ(at_c(p, c), 0.375f) << c;
  EXPECT_FLOAT_EQ(at_c(p, 135), 0.5f);
  EXPECT_FLOAT_EQ(at_c(p, 270), 1.0f);
  EXPECT_FLOAT_EQ(at_c(p, 180), 0.25f);
}

TEST(IesProfile, BilateralSymmetry) {
  const IesProfile p = IesProfile::parse(ies_text({0, 90}, {0, 90, 180}, {10, 10, 20, 20, 40, 40}), "b.ies");
  EXPECT_FLOAT_EQ(at_c(p, 135), 0.75f);
  EXPECT_FLOAT_EQ(at_c(p, 225), 0.75f);   // mirrored to 135
  EXPECT_FLOAT_EQ(at_c(p, 315), 0.375f);  // mirrored to 45
  EXPECT_FLOAT_EQ(at_c(p, 270), 0.5f);
}

TEST(IesProfile, FullTable) {
  const IesProfile p =
      IesProfile::parse(ies_text({0, 90}, {0, 90, 180, 270, 360}, {10, 10, 20, 20, 30, 30, 40, 40, 10, 10}), "f.ies");
  EXPECT_FLOAT_EQ(at_c(p, 315), 0.625f);
  EXPECT_FLOAT_EQ(at_c(p, -45), 0.625f);
  EXPECT_FLOAT_EQ(at_c(p, 225), 0.875f);
  EXPECT_FLOAT_EQ(at_c(p, 45), 0.375f);
}

TEST(IesProfile, EvalTakesDirectionsInTheLuminaireFrame) {
  const IesProfile p = IesProfile::parse(
      ies_text({0, 60, 120}, {0, 90, 180, 270, 360}, {10, 10, 10, 20, 20, 20, 30, 30, 30, 40, 40, 40, 10, 10, 10}),
      "f.ies");
  // z is the nadir, x is C = 0, y is C = 90.
  const double theta = 50 * M_PI / 180, c = 200 * M_PI / 180;
  const Vec3 w(float(std::sin(theta) * std::cos(c)), float(std::sin(theta) * std::sin(c)), float(std::cos(theta)));
  EXPECT_NEAR(p.eval(w), p.eval_angles(50, 200), 1e-5);
  EXPECT_NEAR(p.eval(w), (30.0 + 10.0 * 20.0 / 90.0) / 40.0, 1e-5);
}

// The sphere integral of the normalised profile against an independent midpoint quadrature of eval_angles over
// theta and C (1800 x 720 cells: its error is O(h^2), about 1e-6 relative here, far below the tolerance 2e-5), and
// against closed forms.
double midpoint_integral(const IesProfile& p, const std::function<double(double)>& weight = {}) {
  const int nt = 1800, nc = 720;
  double sum = 0;
  for (int i = 0; i < nt; ++i) {
    const double theta = (i + 0.5) * 180.0 / nt;
    double row = 0;
    for (int j = 0; j < nc; ++j) row += p.eval_angles(theta, (j + 0.5) * 360.0 / nc);
    const double ct = std::cos(theta * M_PI / 180);
    sum += row / nc * std::sin(theta * M_PI / 180) * (weight ? weight(ct) : 1.0);
  }
  return 2 * M_PI * sum * (M_PI / nt);
}

const std::string kFull = ies_text(
    {0, 20, 45, 90, 135, 180}, {0, 90, 180, 270, 360},
    {50, 45, 30, 10, 2, 0, 60, 50, 25, 5, 1, 0, 80, 60, 20, 8, 0, 0, 40, 30, 10, 0, 0, 0, 50, 45, 30, 10, 2, 0});

TEST(IesProfile, IntegralMatchesQuadratureAndClosedForms) {
  EXPECT_NEAR(IesProfile::parse(ies_text({0, 180}, {0}, {7, 7}), "c.ies").integral(), 4 * M_PI, 1e-9);
  EXPECT_NEAR(IesProfile::parse(ies_text({0, 90}, {0}, {7, 7}), "h.ies").integral(), 2 * M_PI, 1e-9);
  for (const std::string& text : {kRound, kFull}) {
    const IesProfile p = IesProfile::parse(text, "p.ies");
    const double expected = midpoint_integral(p);
    EXPECT_NEAR(p.integral(), expected, 2e-5 * expected);
  }
}

// A light's intensity towards a direction from its sample: radiance x r^2.
TEST(IesProfile, PointLightSamplesCandelaOverDistanceSquared) {
  auto profile = std::make_shared<const IesProfile>(IesProfile::parse(kFull, "f.ies"));
  const Rgb I(2.0f, 1.0f, 0.5f);
  const PointLight light(Vec3(1, 2, 3), I, profile, Vec3(0, -1, 0));
  // Nadir -y: C = 0 is +x, C = 90 is -z.
  for (const auto& [theta_deg, c_deg] : {std::pair{0.0, 0.0}, {20.0, 90.0}, {30.0, 45.0}, {100.0, 300.0}}) {
    const double theta = theta_deg * M_PI / 180, c = c_deg * M_PI / 180, r = 2.5;
    const Vec3d w(std::sin(theta) * std::cos(c), -std::cos(theta), -std::sin(theta) * std::sin(c));
    const LightSample ls = light.sample({Vec3(1, 2, 3) + Vec3(w * r), Vec3(0.0f)}, Vec2(0.5f));
    const double expected = profile->eval_angles(theta_deg, c_deg) / (r * r);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(ls.radiance[k], I[k] * expected, 1e-5 * I[k]) << theta_deg << " " << c_deg;
  }
  // At C = 0, theta = 20: the table value 45 over the peak 80.
  const LightSample ls = light.sample(
      {Vec3(1, 2, 3) + 2.0f * Vec3(std::sin(0.349066f), -std::cos(0.349066f), 0.0f), Vec3(0.0f)}, Vec2(0.5f));
  EXPECT_NEAR(ls.radiance[0], 2.0 * 45.0 / 80.0 / 4.0, 1e-5);
  EXPECT_NEAR(light.power()[0], 2.0 * profile->integral(), 1e-5 * light.power()[0]);
}

TEST(IesProfile, SpotLightMultipliesTheFalloff) {
  auto profile = std::make_shared<const IesProfile>(IesProfile::parse(kFull, "f.ies"));
  const SpotLight light(Vec3(0.0f), Vec3(1, 0, 0), Rgb(3.0f), 60.0f, 30.0f, profile);
  const SpotLight plain(Vec3(0.0f), Vec3(1, 0, 0), Rgb(3.0f), 60.0f, 30.0f);
  // Nadir +x (along the x axis): C = 0 is +z, C = 90 is +y.
  for (const auto& [theta_deg, c_deg] : {std::pair{10.0, 30.0}, {40.0, 200.0}, {55.0, 100.0}, {70.0, 0.0}}) {
    const double theta = theta_deg * M_PI / 180, c = c_deg * M_PI / 180, r = 1.5;
    const Vec3d w(std::cos(theta), std::sin(theta) * std::sin(c), std::sin(theta) * std::cos(c));
    const LightSampleContext ctx{Vec3(w * r), Vec3(0.0f)};
    const double expected = profile->eval_angles(theta_deg, c_deg) * plain.sample(ctx, Vec2(0.5f)).radiance[0];
    EXPECT_NEAR(light.sample(ctx, Vec2(0.5f)).radiance[0], expected, 1e-5 * 3.0) << theta_deg << " " << c_deg;
  }
  const double cc = std::cos(M_PI / 3), cf = std::cos(M_PI / 6);
  const auto smooth = [&](double x) {
    if (x >= cf) return 1.0;
    if (x <= cc) return 0.0;
    const double t = (x - cc) / (cf - cc);
    return t * t * (3 - 2 * t);
  };
  const double expected = 3.0 * midpoint_integral(*profile, smooth);
  EXPECT_NEAR(light.power()[0], expected, 2e-5 * expected);
}

// A scene with one light, the profile file beside it.
std::unique_ptr<Scene> load_with(const std::string& light) {
  const std::string json = fmt::format(R"({{
  "camera": {{"position": [0, 1, 5], "look_at": [0, 0, 0], "resolution": [8, 8]}},
  "materials": {{"m": {{"type": "diffuse"}}}},
  "shapes": [{{"type": "sphere", "center": [0, -50, 0], "radius": 0.5, "material": "m"}}],
  "lights": [{}]
}})",
                                       light);
  return load_scene_text(json, "scene.json", ::testing::TempDir());
}

std::string load_error(const std::string& light) {
  try {
    load_with(light);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(loaded)";
}

TEST(IesProfile, PowerIncludesTheProfile) {
  write_file("full.ies", kFull);
  const double integral = IesProfile::parse(kFull, "f.ies").integral();
  const auto scene = load_with(R"({"type": "point", "position": [0, 0, 0], "profile": "full.ies", "power": 100,
                                   "direction": [0, 0, 1]},
                                  {"type": "spot", "position": [0, 0, 0], "profile": "full.ies", "power": 100,
                                   "direction": [0, 0, 1], "cone_angle": 50, "falloff_angle": 20})");
  ASSERT_EQ(scene->lights.size(), 2u);
  EXPECT_NEAR(scene->lights[0]->power()[0], 100.0, 1e-4);
  EXPECT_NEAR(scene->lights[1]->power()[0], 100.0, 1e-4);
  // The peak intensity of the point light is power over the integral: straight along the nadir (+z), C = 0 at 80 cd.
  const LightSample ls = scene->lights[0]->sample({Vec3(0, 0, 2), Vec3(0.0f)}, Vec2(0.5f));
  EXPECT_NEAR(ls.radiance[0], 100.0 / integral * (50.0 / 80.0) / 4.0, 1e-6);
}

TEST(IesProfile, DirectionWithoutAProfileIsWarnedAbout) {
  const auto scene = load_with(R"({"type": "point", "position": [0, 0, 0], "intensity": 1, "direction": [1, 0, 0]})");
  ASSERT_EQ(scene->warnings.size(), 1u);
  EXPECT_EQ(scene->warnings[0],
            "scene.json: /lights/0/direction: 'direction' orients a 'profile' and has no effect without one");
}

// A 100-byte header promising 10^4 x 10^4 candela values allocated 762 MB before failing: the counts are compared
// with the bytes left (each value needs 2) before anything is allocated.
TEST(IesProfile, PromisedCountsAreCheckedAgainstTheFileSize) {
  const size_t rss_before = peak_rss_bytes();
  EXPECT_EQ(parse_error("TILT=NONE\n1 1000 1 10000 10000 1 2 0 0 0\n1 1 60\n0 90\n0\n1 1\n"),
            "lamp.ies: the header promises 10000 vertical and 10000 horizontal angles and 100000000 candela values, "
            "but only 12 bytes follow (each value needs at least 2): truncated or corrupt");
  EXPECT_LT(peak_rss_bytes(), rss_before + (size_t{64} << 20));
  // Enough text for the values promised passes the check.
  EXPECT_EQ(parse_error("TILT=NONE\n1 1000 1 1 1 1 2 0 0 0\n1 1 60 0 0 1"), "(parsed)");
}

TEST(IesProfile, FileErrors) {
  EXPECT_EQ(parse_error(ies_text({0, 30, 60, 90}, {0, 90}, {1, 2, 3, 4, 5})),
            "lamp.ies: expected 8 candela values (2 horizontal x 4 vertical angles), found 5");
  EXPECT_EQ(parse_error(ies_text({0, 30}, {0}, {1, 2, 3})),
            "lamp.ies: expected 2 candela values (1 horizontal x 2 vertical angles), found more");
  // A billion angles is refused before anything is allocated for them.
  EXPECT_EQ(parse_error("TILT=NONE\n1 1000 1 1000000000 1 1 2 0 0 0\n1 1 60\n0 90\n0\n1 1\n"),
            "lamp.ies: the number of vertical angles is 1e+09; expected an integer in [1, 10000]");
  EXPECT_EQ(parse_error("TILT=NONE\n1 1000 1 2 0 1 2 0 0 0\n1 1 60\n0 90\n0\n1 1\n"),
            "lamp.ies: the number of horizontal angles is 0; expected an integer in [1, 10000]");
  EXPECT_EQ(parse_error(ies_text({0, 30, 30}, {0}, {1, 2, 3})),
            "lamp.ies: vertical angles must be strictly increasing: angle 3 is 30 after 30");
  EXPECT_EQ(parse_error(ies_text({0, 90}, {0, 90, 45}, {1, 1, 1, 1, 1, 1})),
            "lamp.ies: horizontal angles must be strictly increasing: angle 3 is 45 after 90");
  EXPECT_EQ(parse_error(ies_text({0, 190}, {0}, {1, 1})),
            "lamp.ies: vertical angles must lie in [0, 180], got 0 to 190");
  EXPECT_EQ(parse_error(ies_text({0, 90}, {0, 120}, {1, 1, 1, 1})),
            "lamp.ies: horizontal angles 0 to 120: kozu reads type C tables from 0 to 0 (rotationally symmetric), 90 "
            "(quadrant), 180 (bilateral) or 360 (full)");
  EXPECT_EQ(parse_error(ies_text({0, 90}, {0}, {1, -1})),
            "lamp.ies: candela value 2 is -1; candela values must be >= 0");
  EXPECT_EQ(parse_error(ies_text({0, 90}, {0}, {0, 0})),
            "lamp.ies: every candela value is 0: the luminaire emits nothing");
  EXPECT_EQ(
      parse_error(ies_text({0, 90}, {0}, {1, 1}, 1.0, "INCLUDE")),
      "lamp.ies: line 4: TILT=INCLUDE is not supported (lamp-tilt factors are not modelled): kozu reads TILT=NONE");
  EXPECT_EQ(parse_error(ies_text({0, 90}, {0}, {1, 1}, 1.0, "NONE", 3)),
            "lamp.ies: photometric type 3 (type A) is not supported: kozu reads type C (1)");
  EXPECT_EQ(parse_error(ies_text({0, 90}, {0}, {1, 1}, 1.0, "NONE", 2)),
            "lamp.ies: photometric type 2 (type B) is not supported: kozu reads type C (1)");
  EXPECT_EQ(parse_error("IESNA:LM-63-2002\n[TEST] x\n"), "lamp.ies: no 'TILT=' line: not an IES LM-63 file");
  EXPECT_EQ(parse_error("TILT=NONE\n1 1000 1 2 1 1 2 0 0 0\n1 1 60\n0 nan\n0\n1 1\n"),
            "lamp.ies: vertical angle 2: expected a finite number, got 'nan'");
  EXPECT_EQ(parse_error("TILT=NONE\n1 1000 1 2 1 1 2 0 0\n"), "lamp.ies: the file ends before the height");
}

TEST(IesProfile, SceneErrorsNameTheFileAndTheJsonPath) {
  const std::filesystem::path bad = write_file("bad.ies", ies_text({0, 30}, {0}, {1}));
  EXPECT_EQ(load_error(R"({"type": "point", "position": [0, 0, 0], "intensity": 1, "profile": "bad.ies"})"),
            fmt::format("scene.json: /lights/0/profile: {}: expected 2 candela values (1 horizontal x 2 vertical "
                        "angles), found 1",
                        bad.string()));
  EXPECT_EQ(load_error(R"({"type": "spot", "position": [0, 0, 0], "direction": [0, -1, 0], "intensity": 1,
                           "profile": "bad.ies"})"),
            fmt::format("scene.json: /lights/0/profile: {}: expected 2 candela values (1 horizontal x 2 vertical "
                        "angles), found 1",
                        bad.string()));
  // Over 16 MiB: refused from its size, before it is read.
  const std::filesystem::path big = std::filesystem::path(::testing::TempDir()) / "big.ies";
  std::filesystem::resize_file(write_file("big.ies", "TILT=NONE\n"), (uint64_t{16} << 20) + 1);
  const std::string e = load_error(R"({"type": "point", "position": [0, 0, 0], "intensity": 1, "profile": "big.ies"})");
  EXPECT_EQ(e.rfind(fmt::format("scene.json: /lights/0/profile: {}: the file is ", big.string()), 0), 0u) << e;
  EXPECT_NE(e.find("kozu reads at most 16"), std::string::npos) << e;
  std::filesystem::remove(big);
  EXPECT_EQ(load_error(R"({"type": "point", "position": [0, 0, 0], "intensity": 1, "profile": "missing.ies"})")
                .rfind("scene.json: /lights/0/profile: ", 0),
            0u);
}

}  // namespace
}  // namespace kozu::test
