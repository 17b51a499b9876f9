// Helpers of the tests that run the kozu command as a process (test_cli_robustness.cpp, test_cli_timing.cpp).
#pragma once

#include "support/render_test.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <string>

namespace kozu::test {

// The kozu binary, quoted for the shell.
inline std::string kozu() { return fmt::format("'{}'", kozu_binary().string()); }

// The sphere studio (scenes/spheres.json, the first built-in demo), quoted: a light scene that loads in
// milliseconds, for the tests of budgets and timing (the built-in demo generates its textures and voxels at load).
inline std::string spheres() { return fmt::format("'{}'", (source_dir() / "scenes/spheres.json").string()); }

inline nlohmann::json read_json(const std::filesystem::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

// Files in a folder whose names contain ".tmp" (kozu's temporary outputs).
inline int temp_files(const std::filesystem::path& dir) {
  int n = 0;
  for (const auto& f : std::filesystem::directory_iterator(dir))
    n += f.path().filename().string().find(".tmp") != std::string::npos;
  return n;
}

// A white furnace: a diffuse sphere of albedo 1 under a uniform unit sky renders 1 in every pixel.
inline constexpr const char* kFurnace = R"({
  "camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov": 35, "resolution": [32, 24]},
  "render": {"spp": 4},
  "materials": {"m": {"type": "diffuse", "albedo": 1}},
  "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}],
  "lights": [{"type": "environment", "radiance": 1}] })";

}  // namespace kozu::test
