// libFuzzer target: the scene parser and loader (JSON text → built Scene). Any input must either load or throw
// InputError; a crash, a sanitizer report, another exception type or a hang is a finding. Files the scene
// names resolve in an empty folder, so fuzzed paths reach only the open-or-explain checks.
#include "core/error.h"
#include "scene/scene_loader.h"

#include <cstdint>
#include <filesystem>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::filesystem::path empty_dir = [] {
    const auto d = std::filesystem::temp_directory_path() / "kozu-fuzz-scene-empty";
    std::filesystem::create_directories(d);
    return d;
  }();
  try {
    kozu::load_scene_text(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.json", empty_dir);
  } catch (const kozu::InputError&) {
  }
  return 0;
}
