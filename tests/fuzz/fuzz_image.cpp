// libFuzzer target: image headers and decoding through read_image (the environment-map reader). The first byte
// picks the file extension, and so the OpenImageIO reader (PFM, PPM, HDR, EXR, PNG); the rest is the file.
// Input loads or throws InputError; the header checks (pixel cap, memory, raw formats against the file length)
// must stop every lying header before an allocation.
#include "core/error.h"
#include "io/image_io.h"

#include <OpenImageIO/imageio.h>

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  // OpenEXR would start and stop a thread pool for every file, which under the sanitizers costs more than the
  // decoding.
  static const bool single_threaded = [] {
    OIIO::attribute("threads", 1);
    OIIO::attribute("exr_threads", 0);
    return true;
  }();
  (void)single_threaded;
  static const char* kExtensions[] = {".pfm", ".ppm", ".hdr", ".exr", ".png"};
  const std::filesystem::path file = std::filesystem::temp_directory_path() /
                                     ("kozu-fuzz-image-" + std::to_string(getpid()) + kExtensions[data[0] % 5]);
  {
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
  }
  try {
    kozu::read_image(file);
  } catch (const kozu::InputError&) {
  }
  std::filesystem::remove(file);
  return 0;
}
