// libFuzzer target: the PLY reader (header, ASCII and both binary byte orders). Input loads or throws InputError.
#include "core/error.h"
#include "io/mesh_io.h"

#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    kozu::parse_ply("fuzz.ply", std::string_view(reinterpret_cast<const char*>(data), size));
  } catch (const kozu::InputError&) {
  }
  return 0;
}
