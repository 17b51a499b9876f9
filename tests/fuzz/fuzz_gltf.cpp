// libFuzzer target: the glTF importer (bytes → GltfScene), each input read both as a .gltf (JSON text) and as a
// .glb (the bytes as they are, and the bytes as the JSON chunk of a well-formed GLB container), so the JSON checks
// before tinygltf, tinygltf itself and the importer's own checks all see it. Any input must either import or throw
// InputError; a crash, a sanitizer report, another exception type or a hang is a finding. Files the input names
// resolve in an empty folder; embedded images are written to a scratch folder.
#include "core/error.h"
#include "io/gltf_reader.h"

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

namespace {

void import(const std::filesystem::path& file, const std::string& bytes, const kozu::GltfImportOptions& options) {
  {
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }
  try {
    kozu::read_gltf(file, options);
  } catch (const kozu::InputError&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::filesystem::path dir = [] {
    const auto d = std::filesystem::temp_directory_path() / "kozu-fuzz-gltf";
    std::filesystem::create_directories(d / "images");
    return d;
  }();
  kozu::GltfImportOptions options;
  options.image_dir = dir / "images";
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  import(dir / "fuzz.gltf", bytes, options);
  import(dir / "fuzz.glb", bytes, options);
  // The input as the JSON chunk of a version-2 GLB with an empty BIN chunk (§4.4).
  std::string json = bytes;
  while (json.size() % 4) json += ' ';
  std::string glb = "glTF";
  const auto u32 = [&glb](uint32_t x) { glb.append(reinterpret_cast<const char*>(&x), 4); };
  u32(2);
  u32(static_cast<uint32_t>(12 + 8 + json.size() + 8 + 4));
  u32(static_cast<uint32_t>(json.size()));
  glb += "JSON";
  glb += json;
  u32(4);
  glb.append("BIN\0", 4);
  glb.append(4, '\0');
  import(dir / "wrapped.glb", glb, options);
  return 0;
}
