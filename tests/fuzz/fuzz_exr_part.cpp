// libFuzzer target: the EXR parts of `kozu merge`: the header read alone (read_image_header: windows, channels,
// kozu attributes, checked before any pixel buffer), then the whole part (read_image_all). Input loads or throws
// InputError.
#include "core/error.h"
#include "io/image_io.h"

#include <OpenImageIO/imageio.h>

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // As in fuzz_image: no OpenEXR thread pool per file.
  static const bool single_threaded = [] {
    OIIO::attribute("threads", 1);
    OIIO::attribute("exr_threads", 0);
    return true;
  }();
  (void)single_threaded;
  const std::filesystem::path file =
      std::filesystem::temp_directory_path() / ("kozu-fuzz-exr-part-" + std::to_string(getpid()) + ".exr");
  {
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    const kozu::Image header = kozu::read_image_header(file);
    if (header.data.empty() && header.channels > 0) kozu::read_image_all(file);
  } catch (const kozu::InputError&) {
  }
  std::filesystem::remove(file);
  return 0;
}
