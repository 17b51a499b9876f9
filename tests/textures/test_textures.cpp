// Textures: the checkerboard's closed-form box filter, image lookups through OpenImageIO's TextureSystem (colour
// spaces, mip level against footprint, channels), the conversion cache and the texture keys' errors.
#include "core/error.h"
#include "core/json_reader.h"
#include "core/rng.h"
#include "io/image_io.h"
#include "scene/scene_loader.h"
#include "support/render_test.h"
#include "textures/checker_texture.h"
#include "textures/image_texture.h"
#include "textures/texture_parse.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>

namespace kozu::test {
namespace {

// The b-fraction of a box by enumerating the unit cells it overlaps: exact, and independent of the separable
// triangle-wave form the texture uses.
double b_fraction_by_cells(double x0, double x1, double y0, double y1) {
  double b = 0;
  for (double i = std::floor(x0); i < x1; ++i)
    for (double j = std::floor(y0); j < y1; ++j) {
      const double w = std::min(x1, i + 1) - std::max(x0, i), h = std::min(y1, j + 1) - std::max(y0, j);
      const bool odd = std::fmod(std::abs(i + j), 2.0) == 1.0;
      if (odd) b += w * h;
    }
  return b / ((x1 - x0) * (y1 - y0));
}

TEST(Checker, BoxFilterMatchesTheCellByCellIntegral) {
  Pcg32 rng(7);
  for (int k = 0; k < 2000; ++k) {
    const double x0 = 40.0 * rng.next_float() - 20.0, y0 = 40.0 * rng.next_float() - 20.0;
    const double w = 6.0 * rng.next_float() + 1e-3, h = 6.0 * rng.next_float() + 1e-3;
    EXPECT_NEAR(CheckerTexture::b_fraction(x0, x0 + w, y0, y0 + h), b_fraction_by_cells(x0, x0 + w, y0, y0 + h), 1e-9)
        << x0 << " " << y0 << " " << w << " " << h;
  }
}

TEST(Checker, PointLookupsGiveTheCellColour) {
  const CheckerTexture c(Vec2(4.0f, 2.0f), Rgb(1, 0, 0), Rgb(0, 0, 1));
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 2; ++j) {
      TextureQuery q;
      q.uv = Vec2((i + 0.5f) / 4.0f, (j + 0.5f) / 2.0f);
      EXPECT_EQ(c.eval(q), (i + j) % 2 == 0 ? Rgb(1, 0, 0) : Rgb(0, 0, 1)) << i << " " << j;
    }
}

// A footprint over many checks converges to the mean (no moiré): within 1/n of 1/2 for a box n checks wide.
TEST(Checker, WideFootprintsGiveTheMean) {
  const CheckerTexture c(Vec2(64.0f), Rgb(1.0f), Rgb(0.0f));
  Pcg32 rng(3);
  for (int k = 0; k < 100; ++k) {
    TextureQuery q;
    q.uv = Vec2(rng.next_float(), rng.next_float());
    q.duvdx = Vec2(0.5f, 0.0f);  // a box 64 checks wide in u
    q.duvdy = Vec2(0.0f, 0.5f);
    EXPECT_NEAR(c.eval(q).r, 0.5f, 1.0f / 64.0f);
  }
}

// Writes a width x height image of `channels` channels from f(x, y, c) in the format of the extension.
template <class F>
std::filesystem::path write_test_image(const std::filesystem::path& file, int width, int height, int channels,
                                       OIIO::TypeDesc format, F&& f) {
  std::vector<float> px(size_t(width) * height * channels);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < channels; ++c) px[(size_t(y) * width + x) * channels + c] = f(x, y, c);
  auto out = OIIO::ImageOutput::create(file.string());
  EXPECT_TRUE(out && out->open(file.string(), OIIO::ImageSpec(width, height, channels, format)));
  EXPECT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, px.data()));
  out->close();
  return file;
}

TextureQuery point(float u, float v) {
  TextureQuery q;
  q.uv = Vec2(u, v);
  return q;
}

TEST(ImageTexture, EightBitColoursAreDecodedFromSrgbAndDataIsNot) {
  TempDir dir;
  TextureCacheOptions o;
  o.convert_dir = dir.path() / "tx";
  TextureCache cache(o);
  const auto png = write_test_image(dir.path() / "grey.png", 16, 16, 3, OIIO::TypeDesc::UINT8,
                                    [](int, int, int) { return 128.0f / 255.0f; });
  const ImageTexture colour(cache, cache.prepare(png, ColorSpace::Auto, TextureUse::Color), {});
  const ImageTexture data(cache, cache.prepare(png, ColorSpace::Auto, TextureUse::Data), {});
  const ImageTexture forced(cache, cache.prepare(png, ColorSpace::Linear, TextureUse::Color), {});
  const float expected = srgb_to_linear(128.0f / 255.0f);                    // 0.2158
  EXPECT_NEAR(colour.eval(point(0.3f, 0.6f)).g, expected, 1.0f / 65535.0f);  // 16-bit precision
  EXPECT_NEAR(data.eval(point(0.3f, 0.6f)).g, 128.0f / 255.0f, 1e-6f);
  EXPECT_NEAR(forced.eval(point(0.3f, 0.6f)).g, 128.0f / 255.0f, 1e-6f);
}

// (u, v) = (0, 0) is the image's bottom-left corner; the left half of the image is red, the top half green.
TEST(ImageTexture, UvOriginIsTheBottomLeftCorner) {
  TempDir dir;
  TextureCache cache;
  const auto exr = write_test_image(dir.path() / "quad.exr", 32, 32, 3, OIIO::TypeDesc::FLOAT, [](int x, int y, int c) {
    return c == 0 ? (x < 16 ? 1.0f : 0.0f) : c == 1 ? (y < 16 ? 1.0f : 0.0f) : 0.0f;
  });
  ImageTexture::Options opt;
  opt.filter = ImageTexture::Filter::Closest;
  const ImageTexture t(cache, cache.prepare(exr, ColorSpace::Auto, TextureUse::Color), opt);
  EXPECT_EQ(t.eval(point(0.25f, 0.25f)), Rgb(1, 0, 0));  // bottom left: red, not green
  EXPECT_EQ(t.eval(point(0.25f, 0.75f)), Rgb(1, 1, 0));  // top left
  EXPECT_EQ(t.eval(point(0.75f, 0.75f)), Rgb(0, 1, 0));  // top right
  EXPECT_EQ(t.eval(point(0.75f, 0.25f)), Rgb(0, 0, 0));
}

// Checks 8 texels wide on a 256² image: a footprint of one texel at a check's centre reads mip levels whose texels
// still lie inside the check (its exact value), one of 64 texels reads a level whose texels average 8 x 8 checks
// (the mean, 1/2), for every filter that uses the mip chain; `closest` ignores the footprint.
TEST(ImageTexture, FootprintSelectsTheMipLevel) {
  TempDir dir;
  TextureCache cache;
  const auto exr = write_test_image(dir.path() / "checks.exr", 256, 256, 1, OIIO::TypeDesc::FLOAT,
                                    [](int x, int y, int) { return float((x / 8 + y / 8) % 2); });
  const auto file = cache.prepare(exr, ColorSpace::Auto, TextureUse::Color);
  for (auto filter : {ImageTexture::Filter::Trilinear, ImageTexture::Filter::Ewa, ImageTexture::Filter::Closest}) {
    ImageTexture::Options opt;
    opt.filter = filter;
    const ImageTexture t(cache, file, opt);
    // The centre of check (2, 3) counted from the top-left, whose value is (2 + 3) % 2 = 1.
    TextureQuery q = point((2 * 8 + 4) / 256.0f, 1.0f - (3 * 8 + 4) / 256.0f);
    q.duvdx = Vec2(1.0f / 256.0f, 0.0f);
    q.duvdy = Vec2(0.0f, 1.0f / 256.0f);
    EXPECT_NEAR(t.eval(q).r, 1.0f, 1e-4f) << int(filter);
    q.duvdx *= 64.0f;
    q.duvdy *= 64.0f;
    EXPECT_NEAR(t.eval(q).r, filter == ImageTexture::Filter::Closest ? 1.0f : 0.5f, 0.02f) << int(filter);
  }
  // The lookups went through the cache: its statistics (kozu render --stats) see them.
  const TextureCache::Stats st = cache.stats();
  EXPECT_GT(st.lookups, 0u);
  EXPECT_GT(st.memory_mb, 0.0);
  EXPECT_GT(st.hit_rate, 0.5);
  EXPECT_EQ(st.files, 1);
}

// At indirect hits (TextureQuery::fine false) an EWA texture looks up as a trilinear one: the same value exactly.
// The footprint is long across vertical stripes, where the two filters differ (EWA keeps the stripes along the
// short axis), so the check sees which one ran.
TEST(ImageTexture, IndirectHitsLookUpTrilinearly) {
  TempDir dir;
  TextureCache cache;
  const auto exr = write_test_image(dir.path() / "stripes.exr", 256, 256, 1, OIIO::TypeDesc::FLOAT,
                                    [](int x, int, int) { return float((x / 4) % 2); });
  const auto file = cache.prepare(exr, ColorSpace::Auto, TextureUse::Color);
  ImageTexture::Options ewa_opt, tri_opt;
  ewa_opt.filter = ImageTexture::Filter::Ewa;
  tri_opt.filter = ImageTexture::Filter::Trilinear;
  const ImageTexture ewa(cache, file, ewa_opt), tri(cache, file, tri_opt);
  TextureQuery q = point((2 * 4 + 2) / 256.0f, 0.5f);  // the centre of a stripe of value 0
  q.duvdx = Vec2(0.0f, 32.0f / 256.0f);                // long along the stripe
  q.duvdy = Vec2(1.0f / 256.0f, 0.0f);                 // a texel across it
  const float fine = ewa.eval(q).r;
  q.fine = false;
  EXPECT_EQ(ewa.eval(q).r, tri.eval(q).r);
  EXPECT_GT(std::abs(ewa.eval(q).r - fine), 0.1f) << "EWA keeps the stripe (" << fine << "), trilinear blurs it";
}

TEST(TextureCache, ConversionsAreReusedWhileTheSourceIsUnchanged) {
  TempDir dir;
  TextureCacheOptions o;
  o.convert_dir = dir.path() / "tx";
  const auto png =
      write_test_image(dir.path() / "a.png", 8, 8, 3, OIIO::TypeDesc::UINT8, [](int x, int, int) { return x / 7.0f; });
  std::filesystem::path first;
  {
    TextureCache cache(o);
    first = cache.prepare(png, ColorSpace::Auto, TextureUse::Color);
    EXPECT_EQ(cache.stats().converted, 1);
    EXPECT_EQ(cache.prepare(png, ColorSpace::Auto, TextureUse::Color), first);
    EXPECT_EQ(cache.stats().reused, 1);
  }
  TextureCache again(o);  // a later run
  EXPECT_EQ(again.prepare(png, ColorSpace::Auto, TextureUse::Color), first);
  EXPECT_EQ(again.stats().converted, 0);
  // A changed source (another size, so the key changes whatever the clock's resolution) is converted anew.
  write_test_image(png, 16, 8, 3, OIIO::TypeDesc::UINT8, [](int, int, int) { return 0.5f; });
  EXPECT_NE(again.prepare(png, ColorSpace::Auto, TextureUse::Color), first);
  EXPECT_EQ(again.stats().converted, 1);
  // The converted file is a tiled mip-mapped texture, used as it is when handed back.
  const ImageInfo info = probe_image(first);
  EXPECT_TRUE(info.tiled);
  EXPECT_GT(info.mip_levels, 1);
  EXPECT_EQ(again.prepare(first, ColorSpace::Linear, TextureUse::Data), first);
}

// The (u, v) a ray from above finds at (x, z) on the scene's only shape.
Vec2 uv_at(const Scene& scene, float x, float z) {
  SurfaceInteraction si;
  EXPECT_TRUE(scene.intersect(Ray{Vec3(x, 5.0f, z), Vec3(0, -1, 0), kInfinity}, si));
  return si.uv;
}

std::unique_ptr<Scene> one_shape(const std::string& shape) {
  return load_scene_text(R"({"camera": {"position": [0, 5, 5], "look_at": [0, 0, 0]},
    "materials": {"m": {"type": "diffuse"}}, "shapes": [)" +
                             shape + "]}",
                         "scene.json", ".");
}

// docs/scene-format.md: a quad's corners v0..v3 map to (0, 0), (1, 0), (1, 1), (0, 1), also under a mirroring
// transform (which reverses the winding); a polygon's to scene units along v1 − v0 and n × that; a sphere is
// latitude-longitude with v = 1 at +y.
TEST(TextureCoordinates, QuadPolygonAndSphereConventions) {
  const std::string quad = R"({"type": "quad", "material": "m",
    "vertices": [[0, 0, 0], [2, 0, 0], [2, 0, -1], [0, 0, -1]]})";
  auto q = one_shape(quad);
  const Vec2 a = uv_at(*q, 0.5f, -0.25f), b = uv_at(*q, 1.5f, -0.75f);
  EXPECT_NEAR(a.x, 0.25f, 1e-5f);
  EXPECT_NEAR(a.y, 0.25f, 1e-5f);
  EXPECT_NEAR(b.x, 0.75f, 1e-5f);
  EXPECT_NEAR(b.y, 0.75f, 1e-5f);
  auto mirrored = one_shape(R"({"type": "quad", "material": "m", "transform": {"scale": [-1, 1, 1]},
    "vertices": [[0, 0, 0], [2, 0, 0], [2, 0, -1], [0, 0, -1]]})");
  const Vec2 m = uv_at(*mirrored, -0.5f, -0.25f);  // the mirror image of a
  EXPECT_NEAR(m.x, 0.25f, 1e-5f);
  EXPECT_NEAR(m.y, 0.25f, 1e-5f);
  auto polygon = one_shape(R"({"type": "polygon", "material": "m",
    "vertices": [[1, 0, 1], [3, 0, 1], [3, 0, -2], [1, 0, -2], [0, 0, 0]]})");
  const Vec2 p = uv_at(*polygon, 2.0f, -1.0f);  // 1 along +x, 2 along n x e_u = (0, 1, 0) x (1, 0, 0) = -z
  EXPECT_NEAR(p.x, 1.0f, 1e-5f);
  EXPECT_NEAR(p.y, 2.0f, 1e-5f);
  auto sphere = one_shape(R"({"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"})");
  EXPECT_NEAR(uv_at(*sphere, 0.0f, 0.0f).y, 1.0f, 1e-3f);  // the +y pole
  const Vec2 s = uv_at(*sphere, 0.0f, 0.999f);  // near the equator towards +z: phi = atan2(-z, x) = 3 pi / 2
  EXPECT_NEAR(s.x, 0.75f, 1e-3f);
  EXPECT_NEAR(s.y, 0.5f, 0.03f);
  // Seen from outside (from -x, y up, so the viewer's right is +z) u grows to the right: images are not mirrored.
  EXPECT_LT(uv_at(*sphere, -0.99f, -0.05f).x, uv_at(*sphere, -0.99f, 0.05f).x);
}

// A diffuse quad under a uniform sky of radiance 1, seen alone, reflects exactly its albedo (NEE and BSDF sampling
// of the cosine lobe are both exact, their MIS weights sum to 1): each quarter of the view shows the texel of the
// 2 x 2 albedo image that the uv convention puts there.
TEST(TexturedMaterial, DiffuseAlbedoFromAnImage) {
  TempDir dir;
  const Rgb texel[2][2] = {{Rgb(0.8f, 0, 0), Rgb(0, 0.6f, 0)}, {Rgb(0, 0, 0.4f), Rgb(0.5f)}};  // [row][column]
  write_test_image(dir.path() / "quads.exr", 2, 2, 3, OIIO::TypeDesc::FLOAT,
                   [&](int x, int y, int c) { return texel[y][x][c]; });
  const TestRender r = render_json(R"({
    "camera": {"position": [0, 0, 1], "look_at": [0, 0, 0], "fov": 40, "resolution": [32, 32]},
    "materials": {"m": {"type": "diffuse",
                        "albedo": {"type": "image", "file": "quads.exr", "filter": "closest"}}},
    "shapes": [{"type": "quad", "material": "m", "vertices": [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]}],
    "lights": [{"type": "environment", "radiance": 1}]})",
                                   4, 2, 0, dir.path());
  const std::vector<float> px = r.film.rgb();
  for (int row = 0; row < 2; ++row)
    for (int col = 0; col < 2; ++col) {
      const size_t i = (size_t(8 + 16 * row) * 32 + size_t(8 + 16 * col)) * 3;
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(px[i + c], texel[row][col][c], 1e-4f) << row << " " << col << " " << c;
    }
}

// dp/du and dp/dv against finite differences of the (u, v) the shapes report, and the footprint of a known cone.
TEST(TextureCoordinates, DerivativesAndFootprints) {
  auto sphere = one_shape(R"({"type": "sphere", "center": [0, 0, 0], "radius": 2, "material": "m"})");
  for (const Vec2 xz : {Vec2(0.3f, 0.5f), Vec2(-0.7f, 0.2f), Vec2(0.1f, -0.9f)}) {
    SurfaceInteraction si;
    ASSERT_TRUE(sphere->intersect(Ray{Vec3(xz.x, 5.0f, xz.y), Vec3(0, -1, 0), kInfinity}, si));
    Vec3 dpdu, dpdv;
    si.shape->uv_derivatives(si, &dpdu, &dpdv);
    const float eps = 1e-3f;
    for (int k = 0; k < 2; ++k) {
      const Vec3 target = glm::normalize(si.p + eps * (k == 0 ? dpdu : dpdv)) * 2.0f;  // back onto the sphere
      SurfaceInteraction moved;
      ASSERT_TRUE(sphere->intersect(Ray{target * 1.5f, -glm::normalize(target), kInfinity}, moved));
      const Vec2 duv = moved.uv - si.uv;
      EXPECT_NEAR(duv[k], eps, 0.05f * eps) << "k " << k;
      EXPECT_NEAR(duv[1 - k], 0.0f, 0.05f * eps) << "k " << k;
    }
  }
  // A 2 x 1 quad (dp/du = (2, 0, 0), dp/dv = (0, 0, -1)) hit at 45 degrees by a ray heading to -z: the cone's
  // ellipse is w sqrt 2 long along -z (v) and w wide along x (u).
  auto quad = one_shape(R"({"type": "quad", "material": "m",
    "vertices": [[0, 0, 0], [2, 0, 0], [2, 0, -1], [0, 0, -1]]})");
  SurfaceInteraction si;
  ASSERT_TRUE(quad->intersect(Ray{Vec3(1.0f, 1.0f, 0.5f), glm::normalize(Vec3(0, -1, -1)), kInfinity}, si));
  si.cone_width = 0.01f;
  Vec2 dx, dy;
  uv_footprint(si, &dx, &dy);
  EXPECT_NEAR(dx.x, 0.0f, 1e-6f);
  EXPECT_NEAR(dx.y, 0.01f * std::sqrt(2.0f), 1e-6f);
  EXPECT_NEAR(std::abs(dy.x), 0.005f, 1e-6f);
  EXPECT_NEAR(dy.y, 0.0f, 1e-6f);
}

// Aliasing: a checkerboard ground plane (a 256² image of 8-texel checks, repeated) under a uniform sky renders its
// filtered albedo exactly (no noise from lighting), so at 1 spp the far rows show only how the texture is filtered.
// Near the horizon each pixel covers many checks: filtered by the camera ray's cone footprint the pixels converge
// to the mean 1/2; the nearest texel (`closest`) gives 0 or 1 at random (moiré).
struct FarRows {
  double mean = 0, spread = 0;  // of the pixels' red channel
};
FarRows render_far_rows(const std::filesystem::path& dir, const std::string& filter) {
  const TestRender r = render_json(R"({
    "camera": {"position": [0, 1, 0], "look_at": [0, 0.6, -10], "fov": 40, "resolution": [128, 64]},
    "materials": {"m": {"type": "diffuse", "albedo": {"type": "image", "file": "checks.exr", "filter": ")" +
                                       filter + R"(", "uv_scale": [100, 100]}}},
    "shapes": [{"type": "quad", "material": "m",
                "vertices": [[-100, 0, 100], [100, 0, 100], [100, 0, -100], [-100, 0, -100]]}],
    "lights": [{"type": "environment", "radiance": 1}]})",
                                   1, 2, 0, dir);
  const std::vector<float> px = r.film.rgb();
  // Rows 31-37 look 1.7 to 5.4 degrees below the horizon: ground 11 to 34 units away, pixels 0.1-0.4 units wide
  // and 3-10 times longer, over checks 1/16 unit wide.
  double sum = 0, sum2 = 0;
  int n = 0;
  for (int y = 31; y <= 37; ++y)
    for (int x = 0; x < 128; ++x) {
      const double v = px[(size_t(y) * 128 + x) * 3];
      sum += v;
      sum2 += v * v;
      ++n;
    }
  FarRows f;
  f.mean = sum / n;
  f.spread = std::sqrt(std::max(0.0, sum2 / n - f.mean * f.mean));
  return f;
}

TEST(TexturedMaterial, CameraRayFootprintsRemoveMoireAtGrazingAngles) {
  TempDir dir;
  write_test_image(dir.path() / "checks.exr", 256, 256, 3, OIIO::TypeDesc::FLOAT,
                   [](int x, int y, int) { return float((x / 8 + y / 8) % 2); });
  const FarRows filtered = render_far_rows(dir.path(), "ewa"), trilinear = render_far_rows(dir.path(), "trilinear"),
                closest = render_far_rows(dir.path(), "closest");
  std::printf(
      "far rows at 1 spp: ewa mean %.4f spread %.4f, trilinear mean %.4f spread %.4f, closest mean %.4f "
      "spread %.4f\n",
      filtered.mean, filtered.spread, trilinear.mean, trilinear.spread, closest.mean, closest.spread);
  EXPECT_NEAR(filtered.mean, 0.5, 0.05);
  EXPECT_LT(filtered.spread, 0.1);
  EXPECT_NEAR(trilinear.mean, 0.5, 0.05);
  EXPECT_LT(trilinear.spread, 0.1);
  EXPECT_GT(closest.spread, 0.3);  // the aliasing the footprints remove
}

// Cones widen after a rough bounce (geometry/ray_cone.h): a rough mirror floor (GGX, roughness 0.5) reflects a
// sunlit wall whose albedo is a fine checkerboard (checks ~0.15 units wide, mean 1/2), seen at 1 spp. Each
// reflected ray's cone is then about 1 rad wide, so the wall's lookups filter to the mean, and the image is as
// smooth as one of a plain wall of albedo 1/2: only the lobe's own sampling noise is left. Point lookups (the
// nearest texel, "closest") make every reflected ray see black or white: noise no filtering would leave.
double reflected_wall_spread(const std::filesystem::path& dir, const std::string& albedo, double* mean) {
  const TestRender r = render_json(R"({
    "camera": {"position": [0, 1, 0], "look_at": [0, 0, -1.2], "fov": 30, "resolution": [64, 48]},
    "render": {"max_depth": 2},
    "materials": {"floor": {"type": "conductor", "roughness": 0.5},
                  "wall": {"type": "diffuse", "albedo": )" + albedo + R"(}},
    "shapes": [{"type": "quad", "material": "floor",
                "vertices": [[-20, 0, 20], [20, 0, 20], [20, 0, -4], [-20, 0, -4]]},
               {"type": "quad", "material": "wall",
                "vertices": [[-20, 0, -4], [20, 0, -4], [20, 20, -4], [-20, 20, -4]]}],
    "lights": [{"type": "directional", "direction": [0, 0, -1], "irradiance": 3.14159265}]})",
                                   1, 2, 0, dir);
  const std::vector<float> px = r.film.rgb();
  double sum = 0, sum2 = 0;
  const size_t n = px.size() / 3;
  for (size_t i = 0; i < n; ++i) {
    sum += px[3 * i];
    sum2 += double(px[3 * i]) * px[3 * i];
  }
  *mean = sum / double(n);
  return std::sqrt(std::max(0.0, sum2 / double(n) - *mean * *mean));
}

TEST(TexturedMaterial, ConesWidenAfterARoughBounce) {
  TempDir dir;
  write_test_image(dir.path() / "checks.exr", 256, 256, 3, OIIO::TypeDesc::FLOAT,
                   [](int x, int y, int) { return float((x / 8 + y / 8) % 2); });
  const auto image = [](const char* filter) {
    return fmt::format(R"({{"type": "image", "file": "checks.exr", "filter": "{}", "uv_scale": [8, 8]}})", filter);
  };
  double mean_plain, mean_ewa, mean_closest;
  const double plain = reflected_wall_spread(dir.path(), "0.5", &mean_plain);
  const double ewa = reflected_wall_spread(dir.path(), image("ewa"), &mean_ewa);
  const double closest = reflected_wall_spread(dir.path(), image("closest"), &mean_closest);
  std::printf("reflected wall at 1 spp: plain mean %.4f spread %.4f, ewa mean %.4f spread %.4f, closest mean %.4f "
              "spread %.4f\n",
              mean_plain, plain, mean_ewa, ewa, mean_closest, closest);
  ASSERT_GT(mean_plain, 0.05);  // the wall is seen in the floor
  EXPECT_LT(ewa, 1.15 * plain);
  EXPECT_GT(closest, 1.5 * plain);  // what the cones remove
  EXPECT_NEAR(mean_ewa, mean_plain, 0.05 * mean_plain);
}

Deferred<Texture> parse_in(const std::string& json, const std::filesystem::path& dir, TextureCache* cache) {
  static std::vector<std::unique_ptr<Json>> keep;  // JsonObject refers to its document
  keep.push_back(std::make_unique<Json>(parse_json_text(json, "scene.json")));
  const JsonObject o(*keep.back(), "/materials/m", std::make_shared<JsonSource>(JsonSource{"scene.json", dir}));
  TextureParseContext ctx;
  if (cache) ctx.cache = [cache] { return cache; };
  ctx.range = Range::unit();
  return parse_texture(o, "albedo", ctx);
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(TextureKeys, ValuesTexturesAndTheirErrors) {
  TempDir dir;
  TextureCache cache;
  write_test_image(dir.path() / "rgb.png", 4, 4, 3, OIIO::TypeDesc::UINT8, [](int, int, int) { return 1.0f; });
  EXPECT_EQ(parse_in(R"({"albedo": 0.5})", dir.path(), &cache).take()->eval({}), Rgb(0.5f));
  EXPECT_EQ(
      parse_in(R"({"albedo": {"type": "constant", "value": [0.1, 0.2, 0.3]}})", dir.path(), &cache).take()->eval({}),
      Rgb(0.1f, 0.2f, 0.3f));
  EXPECT_EQ(error_of([&] { parse_in(R"({"albedo": 1.5})", dir.path(), &cache); }),
            "scene.json: /materials/m/albedo: expected a number in [0, 1], got 1.5");
  EXPECT_EQ(error_of([&] { parse_in(R"({"albedo": {"type": "wood"}})", dir.path(), &cache); }),
            "scene.json: /materials/m/albedo/type: unknown value 'wood' (expected one of 'image', 'checker', "
            "'constant', 'wwii_gloss_combine')");
  EXPECT_EQ(error_of([&] {
              parse_in(R"({"albedo": {"type": "checker", "size": 3}})", dir.path(), &cache);
            }).rfind("scene.json: /materials/m/albedo/size: unknown key 'size'", 0),
            0u);
  // Files are read by the load job, and their errors name the key.
  Deferred<Texture> missing = parse_in(R"({"albedo": {"type": "image", "file": "nope.png"}})", dir.path(), &cache);
  EXPECT_TRUE(missing.needs_load());
  EXPECT_EQ(error_of([&] { missing.take(); }).rfind("scene.json: /materials/m/albedo/file: ", 0), 0u);
  Deferred<Texture> alpha =
      parse_in(R"({"albedo": {"type": "image", "file": "rgb.png", "channel": "a"}})", dir.path(), &cache);
  EXPECT_EQ(error_of([&] { alpha.take(); }), "scene.json: /materials/m/albedo/channel: rgb.png has 3 channels");
}

// uv_rotation turns the scaled coordinates counter-clockwise before the offset, (s, 1 − t) = R(ρ)(su u, sv v) + o
// (glTF's KHR_texture_transform), and an rgb "scale" multiplies each channel. On the image whose left half is red
// and top half green, ρ = 90° takes (u, v) = (0.75, 0.75) to (−0.75, 0.75), i.e. s = 0.25 (wrapped), t = 0.25: the
// top-left quadrant, yellow.
TEST(ImageTexture, UvRotationAndRgbScale) {
  TempDir dir;
  TextureCache cache;
  write_test_image(dir.path() / "quad.exr", 32, 32, 3, OIIO::TypeDesc::FLOAT, [](int x, int y, int c) {
    return c == 0 ? (x < 16 ? 1.0f : 0.0f) : c == 1 ? (y < 16 ? 1.0f : 0.0f) : 0.0f;
  });
  ImageTexture::Options turned;
  turned.uv_rotation = 0.5f * kPi;
  const Vec2 st = ImageTexture::lookup_coordinates(turned, Vec2(0.75f, 0.75f));
  EXPECT_NEAR(st.x, -0.75f, 1e-6f);
  EXPECT_NEAR(st.y, 0.25f, 1e-6f);
  const std::string json = R"({"albedo": {"type": "image", "file": "quad.exr", "filter": "closest",
      "uv_rotation": 1.5707963267948966, "scale": [1, 0.5, 0.25]}})";
  const std::unique_ptr<Texture> t = parse_in(json, dir.path(), &cache).take();
  const Rgb yellow = t->eval(point(0.75f, 0.75f));
  EXPECT_EQ(yellow, Rgb(1.0f, 0.5f, 0.0f));
  // Without rotation the same point is the top-right quadrant (green only).
  const std::unique_ptr<Texture> plain =
      parse_in(R"({"albedo": {"type": "image", "file": "quad.exr", "filter": "closest", "scale": [1, 0.5, 0.25]}})",
               dir.path(), &cache)
          .take();
  EXPECT_EQ(plain->eval(point(0.75f, 0.75f)), Rgb(0.0f, 0.5f, 0.0f));
  // threshold: after the scale, 0.5 reaches 0.5 (1) and 0 does not (0).
  const std::unique_ptr<Texture> cut =
      parse_in(R"({"albedo": {"type": "image", "file": "quad.exr", "filter": "closest", "scale": [1, 0.5, 0.25],
                   "threshold": 0.5}})",
               dir.path(), &cache)
          .take();
  EXPECT_EQ(cut->eval(point(0.75f, 0.75f)), Rgb(0.0f, 1.0f, 0.0f));
  EXPECT_EQ(cut->eval(point(0.25f, 0.75f)), Rgb(1.0f, 1.0f, 0.0f));  // top left: (1, 0.5, 0)
  EXPECT_EQ(error_of([&] {
              parse_in(R"({"albedo": {"type": "image", "file": "quad.exr", "scale": [1, 2]}})", dir.path(), &cache);
            }).rfind("scene.json: /materials/m/albedo/scale: expected [r, g, b] or a number", 0),
            0u);
}

}  // namespace
}  // namespace kozu::test
