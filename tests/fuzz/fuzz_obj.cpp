// libFuzzer target: the OBJ reader (pre-scan and tinyobjloader). Input loads or throws InputError.
#include "core/error.h"
#include "io/mesh_io.h"

#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    kozu::parse_obj("fuzz.obj", std::string(reinterpret_cast<const char*>(data), size));
  } catch (const kozu::InputError&) {
  }
  return 0;
}
