#include "textures/procedural_image.h"

#include "core/error.h"
#include "core/math.h"
#include "core/rng.h"
#include "io/image_io.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>
#include <stdexcept>

namespace kozu {

namespace {

float fract(float x) { return x - std::floor(x); }
Vec3 lerp3(const Vec3& a, const Vec3& b, float t) { return a + (b - a) * t; }

// Smooth value noise on a periodic lattice of `period` cells, in [0, 1).
float value_noise(float x, float y, int period, uint32_t seed) {
  const int i = static_cast<int>(std::floor(x)), j = static_cast<int>(std::floor(y));
  const float fx = x - static_cast<float>(i), fy = y - static_cast<float>(j);
  const float sx = fx * fx * (3 - 2 * fx), sy = fy * fy * (3 - 2 * fy);
  auto h = [&](int a, int b) {
    const auto wrap = [&](int v) { return static_cast<uint32_t>(((v % period) + period) % period); };
    return u32_to_unit_float(hash_combine(hash_combine(seed, wrap(a)), wrap(b)));
  };
  const float top = h(i, j) + (h(i + 1, j) - h(i, j)) * sx;
  const float bottom = h(i, j + 1) + (h(i + 1, j + 1) - h(i, j + 1)) * sx;
  return top + (bottom - top) * sy;
}

// ---- cobblestones -------------------------------------------------------------------------------------------------

struct Cobbles {
  int n = 0;
  std::vector<float> height;  // texel widths
  std::vector<float> joint;   // 1 inside a stone, 0 in its joint
  std::vector<int> stone;     // the stone's index, cells × cells
};

// Heights of `cells` × `cells` jittered Voronoi stones tiling the n × n square periodically: the distance to the
// bisector with the second-nearest stone says how far inside its stone a texel is; the profile over it is a
// circular shoulder, each stone tilted a little and of its own height.
Cobbles cobbles(int n, int cells) {
  Pcg32 rng(4);
  std::vector<Vec2> site(static_cast<size_t>(cells) * cells);
  std::vector<Vec3> tilt(site.size());
  for (int j = 0; j < cells; ++j)
    for (int i = 0; i < cells; ++i)
      site[static_cast<size_t>(j) * cells + i] = Vec2(static_cast<float>(i) + 0.15f + 0.7f * rng.next_float(),
                                                      static_cast<float>(j) + 0.15f + 0.7f * rng.next_float());
  for (Vec3& t : tilt)
    t = Vec3(-0.05f + 0.1f * rng.next_float(), -0.05f + 0.1f * rng.next_float(), 0.8f + 0.4f * rng.next_float());
  Cobbles c;
  c.n = n;
  c.height.resize(static_cast<size_t>(n) * n);
  c.joint.resize(c.height.size());
  c.stone.resize(c.height.size());
  const float cell = static_cast<float>(n) / static_cast<float>(cells);
  const float dome = 0.16f * cell;  // a stone's crown above its joint, in texels
  tbb::parallel_for(0, n, [&](int y) {
    for (int x = 0; x < n; ++x) {
      const Vec2 p((static_cast<float>(x) + 0.5f) / cell, (static_cast<float>(y) + 0.5f) / cell);
      const int cx = static_cast<int>(p.x), cy = static_cast<int>(p.y);
      float d1 = 1e9f, d2 = 1e9f;
      Vec2 s1(0.0f), s2(0.0f);
      int k1 = 0;
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
          const int i = cx + di, j = cy + dj;
          const int wi = ((i % cells) + cells) % cells, wj = ((j % cells) + cells) % cells;
          const Vec2 s =
              site[static_cast<size_t>(wj) * cells + wi] + Vec2(static_cast<float>(i - wi), static_cast<float>(j - wj));
          const float d = glm::dot(p - s, p - s);
          if (d < d1) {
            d2 = d1, s2 = s1;
            d1 = d, s1 = s, k1 = wj * cells + wi;
          } else if (d < d2) {
            d2 = d, s2 = s;
          }
        }
      const Vec2 e = s2 - s1;
      const float edge = glm::dot(p - 0.5f * (s1 + s2), -e) / std::max(glm::length(e), 1e-6f);  // > 0: inside
      const float t = std::clamp(edge / 0.45f, 0.0f, 1.0f);
      const float profile = std::sqrt(t * (2.0f - t));
      const Vec3& tl = tilt[static_cast<size_t>(k1)];
      const size_t o = static_cast<size_t>(y) * n + x;
      const bool inside = edge > 0.02f;
      c.height[o] = inside ? dome * (tl.z * profile + tl.x * (p.x - s1.x) * 4.0f + tl.y * (p.y - s1.y) * 4.0f) : 0.0f;
      c.joint[o] = inside ? 1.0f : 0.0f;
      c.stone[o] = k1;
    }
  });
  return c;
}

ProceduralImage cobblestone_normal(int n) {
  const Cobbles c = cobbles(n, 8);
  ProceduralImage img{n, n, std::vector<float>(3 * static_cast<size_t>(n) * n)};
  auto h = [&](int x, int y) { return c.height[static_cast<size_t>((y + n) % n) * n + (x + n) % n]; };
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      // Rows run down the image, the map's +y (OpenGL) up it.
      const float dx = 0.5f * (h(x + 1, y) - h(x - 1, y)), dy = 0.5f * (h(x, y + 1) - h(x, y - 1));
      const Vec3 nrm = glm::normalize(Vec3(-dx, dy, 1.0f));
      for (int k = 0; k < 3; ++k) img.rgb[3 * (static_cast<size_t>(y) * n + x) + k] = 0.5f * (nrm[k] + 1.0f);
    }
  return img;
}

ProceduralImage cobblestone_albedo(int n) {
  const Cobbles c = cobbles(n, 8);
  ProceduralImage img{n, n, std::vector<float>(3 * static_cast<size_t>(n) * n)};
  const Vec3 basalt(0.16f, 0.14f, 0.12f), mortar(0.05f, 0.045f, 0.04f);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const size_t o = static_cast<size_t>(y) * n + x;
      const uint32_t s = hash_u32(static_cast<uint32_t>(c.stone[o]) + 0x636f62u);
      const float shade = 0.7f + 0.6f * u32_to_unit_float(s);
      const float warm = -0.1f + 0.2f * u32_to_unit_float(hash_u32(s));
      // Grain within a stone: 16-cell value noise.
      const float g = 0.85f + 0.3f * value_noise(16.0f * static_cast<float>(x) / static_cast<float>(n),
                                                 16.0f * static_cast<float>(y) / static_cast<float>(n), 16, 0x67726eu);
      Vec3 stone = basalt * shade * g * Vec3(1.0f + warm, 1.0f, 1.0f - warm);
      const Vec3 v = lerp3(mortar, stone, c.joint[o]);
      for (int k = 0; k < 3; ++k) img.rgb[3 * o + k] = std::clamp(v[k], 0.0f, 1.0f);
    }
  return img;
}

// ---- stained glass ------------------------------------------------------------------------------------------------

ProceduralImage stained_glass(int n) {
  const Vec3 ruby(0.75f, 0.04f, 0.06f), cobalt(0.05f, 0.16f, 0.85f), amber(0.95f, 0.55f, 0.08f),
      emerald(0.07f, 0.58f, 0.2f), violet(0.42f, 0.1f, 0.7f), pale(0.9f, 0.84f, 0.66f);
  const std::array<Vec3, 6> outer = {emerald, violet, amber, cobalt, ruby, pale};
  // Radii (of the unit square's half width 0.5): centre disc, petals, outer ring's split, outer ring, rim.
  constexpr float r0 = 0.12f, r1 = 0.29f, r15 = 0.375f, r2 = 0.455f, r3 = 0.48f;
  constexpr float lead = 0.0065f;  // half width of the came, in texture units
  ProceduralImage img{n, n, std::vector<float>(3 * static_cast<size_t>(n) * n)};
  tbb::parallel_for(0, n, [&](int y) {
    for (int x = 0; x < n; ++x) {
      const float u = (static_cast<float>(x) + 0.5f) / static_cast<float>(n) - 0.5f;
      const float v = 0.5f - (static_cast<float>(y) + 0.5f) / static_cast<float>(n);
      const float r = std::sqrt(u * u + v * v);
      float theta = std::atan2(v, u) + kPi / 2;  // 0 at the top
      if (theta < 0) theta += kTwoPi;
      Vec3 glass(0.0f);
      float to_lead = 0.0f;  // distance to the nearest came
      uint32_t pane = 0;
      if (r < r0) {
        glass = amber;
        to_lead = r0 - r;
        pane = 1;
      } else if (r < r1) {
        const float sector = theta / (kTwoPi / 12.0f);
        const int s = static_cast<int>(sector) % 12;
        const float f = fract(sector);
        glass = s % 2 == 0 ? ruby : cobalt;
        to_lead = std::min({r - r0, r1 - r, std::min(f, 1.0f - f) * (kTwoPi / 12.0f) * r});
        pane = 2 + static_cast<uint32_t>(s);
      } else if (r < r2) {
        const float sector = theta / (kTwoPi / 24.0f) + 0.5f;
        const int s = static_cast<int>(sector) % 24;
        const float f = fract(sector);
        const bool inner = r < r15;
        glass = outer[static_cast<size_t>((s + (inner ? 0 : 3)) % 6)];
        to_lead = std::min({r - r1, r2 - r, std::abs(r - r15), std::min(f, 1.0f - f) * (kTwoPi / 24.0f) * r});
        pane = 20 + static_cast<uint32_t>(2 * s + (inner ? 0 : 1));
      }
      Vec3 c(0.0f);
      if (r < r2 && to_lead > lead) {
        // Each pane a little lighter or darker, the glass mottled.
        const float pane_shade = 0.8f + 0.4f * u32_to_unit_float(hash_u32(pane * 2654435761u));
        const float m = 0.75f + 0.5f * value_noise(48.0f * (u + 0.5f), 48.0f * (v + 0.5f), 48, 0x676c73u);
        c = glass * pane_shade * m;
      } else if (r < r3) {
        c = Vec3(0.012f);  // lead: a little light leaks round the came
      }
      const size_t o = static_cast<size_t>(y) * n + x;
      for (int k = 0; k < 3; ++k) img.rgb[3 * o + k] = std::clamp(c[k], 0.0f, 1.0f);
    }
  });
  return img;
}

// ---- dusk sky -----------------------------------------------------------------------------------------------------

ProceduralImage dusk_sky(int resolution) {
  const int w = resolution, h = std::max(1, resolution / 2);
  ProceduralImage img{w, h, std::vector<float>(3 * static_cast<size_t>(w) * h)};
  const float elev = 3.0f * kPi / 180.0f;
  const Vec3 sun(0.0f, std::sin(elev), -std::cos(elev));
  const Vec3 horizon(1.1f, 0.62f, 0.36f), zenith(0.22f, 0.36f, 0.66f), ground(0.05f, 0.045f, 0.04f);
  for (int j = 0; j < h; ++j) {
    const float theta = (static_cast<float>(j) + 0.5f) / static_cast<float>(h) * kPi;
    for (int i = 0; i < w; ++i) {
      // kozu's lat-long mapping (lights/environment.h): u = 0.5 looks down −z.
      const float phi = ((static_cast<float>(i) + 0.5f) / static_cast<float>(w) - 0.5f) * kTwoPi;
      const Vec3 d(std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi));
      Vec3 c;
      if (d.y < 0.0f) {
        c = lerp3(horizon * 0.25f, ground, std::min(1.0f, -d.y * 8.0f));
      } else {
        const float t = 1.0f - std::pow(1.0f - d.y, 3.0f);
        c = lerp3(horizon, zenith, t);
      }
      const float cosg = std::max(0.0f, glm::dot(d, sun));
      c += (2.5f * std::pow(cosg, 64.0f) + 0.6f * std::pow(cosg, 8.0f)) * Vec3(1.0f, 0.7f, 0.45f);
      const size_t o = static_cast<size_t>(j) * w + i;
      for (int k = 0; k < 3; ++k) img.rgb[3 * o + k] = c[k];
    }
  }
  return img;
}

using Generator = ProceduralImage (*)(int);
struct Entry {
  const char* name;
  Generator make;
};
constexpr Entry kImages[] = {
    {"cobblestone_normal", &cobblestone_normal},
    {"cobblestone_albedo", &cobblestone_albedo},
    {"stained_glass", &stained_glass},
    {"dusk_sky", &dusk_sky},
};

std::mutex& generate_mutex() {
  static std::mutex m;
  return m;
}

}  // namespace

const std::vector<std::string>& procedural_image_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (const Entry& e : kImages) v.emplace_back(e.name);
    return v;
  }();
  return names;
}

ProceduralImage make_procedural_image(std::string_view name, int resolution) {
  if (resolution < kProceduralImageMinResolution || resolution > kProceduralImageMaxResolution)
    throw std::invalid_argument(fmt::format("resolution {} is outside [{}, {}]", resolution,
                                            kProceduralImageMinResolution, kProceduralImageMaxResolution));
  for (const Entry& e : kImages)
    if (name == e.name) return e.make(resolution);
  throw std::invalid_argument(
      fmt::format("unknown procedural image \"{}\" (known: {})", name, fmt::join(procedural_image_names(), ", ")));
}

std::filesystem::path procedural_image_file(std::string_view name, int resolution,
                                            const std::filesystem::path& folder) {
  const std::filesystem::path file =
      folder / "procedural" / fmt::format("{}-{}-v{}.exr", name, resolution, kProceduralImageVersion);
  // One generation at a time in this process; other processes are kept apart by write_image's rename.
  std::lock_guard lock(generate_mutex());
  std::error_code ec;
  if (std::filesystem::is_regular_file(file, ec)) return file;
  const ProceduralImage img = make_procedural_image(name, resolution);
  std::filesystem::create_directories(file.parent_path(), ec);
  if (ec)
    throw std::runtime_error(
        fmt::format("{}: cannot create the folder: {}", file.parent_path().string(), ec.message()));
  write_image(file, img.width, img.height, img.rgb, ToneMap{});
  return file;
}

void expand_procedural_images(Json& root, const std::string& display_name, const std::filesystem::path& folder) {
  std::vector<std::pair<Json*, std::string>> stack = {{&root, ""}};
  while (!stack.empty()) {
    auto [node, path] = stack.back();
    stack.pop_back();
    if (node->is_object()) {
      const auto type = node->find("type");
      const auto proc = node->find("procedural");
      if (proc != node->end() && type != node->end() && type->is_string() &&
          (*type == "image" || *type == "environment")) {
        const std::string key = json_pointer_append(path, "procedural");
        if (node->contains("file"))
          throw InputError(display_name, key, "give either \"file\" or \"procedural\", not both");
        if (!proc->is_string())
          throw InputError(
              display_name, key,
              fmt::format("expected the name of a procedural image ({})", fmt::join(procedural_image_names(), ", ")));
        int resolution = kProceduralImageDefaultResolution;
        if (const auto res = node->find("resolution"); res != node->end()) {
          if (!res->is_number_integer())
            throw InputError(display_name, json_pointer_append(path, "resolution"), "expected an integer");
          const int64_t r = res->get<int64_t>();
          if (r < kProceduralImageMinResolution || r > kProceduralImageMaxResolution)
            throw InputError(
                display_name, json_pointer_append(path, "resolution"),
                fmt::format("{} is outside [{}, {}]", r, kProceduralImageMinResolution, kProceduralImageMaxResolution));
          resolution = static_cast<int>(r);
        }
        const std::string name = proc->get<std::string>();
        std::filesystem::path file;
        try {
          file = procedural_image_file(name, resolution, folder);
        } catch (const std::exception& e) {
          throw InputError(display_name, key, e.what());
        }
        std::error_code ec;
        const std::filesystem::path absolute = std::filesystem::absolute(file, ec);
        node->erase("procedural");
        node->erase("resolution");
        (*node)["file"] = (ec ? file : absolute).string();
        continue;
      }
      for (auto it = node->begin(); it != node->end(); ++it)
        stack.emplace_back(&it.value(), json_pointer_append(path, it.key()));
    } else if (node->is_array()) {
      for (size_t i = 0; i < node->size(); ++i) stack.emplace_back(&(*node)[i], json_pointer_append(path, i));
    }
  }
}

}  // namespace kozu
