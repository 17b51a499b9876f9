// libFuzzer target: IES LM-63 photometric files (IesProfile::parse, the "profile" of point and spot lights), then
// the profile's lookups and integral. Input parses or throws std::runtime_error; the counts a header promises are
// checked against the text left before anything is allocated.
#include "lights/ies_profile.h"

#include <cstdint>
#include <stdexcept>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const kozu::IesProfile p =
        kozu::IesProfile::parse(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.ies");
    p.eval(kozu::Vec3(0.0f, 0.6f, 0.8f));
    p.eval_angles(45.0, 200.0);
    p.integral();
  } catch (const std::runtime_error&) {
  }
  return 0;
}
