// libFuzzer target: checkpoint files (`kozu render --resume`): the container (lengths against the file's size, the
// hash), the header's identity, and every value of the payload (check_film_values). The render expected is the
// one the header names, so a file that passes the container's checks reaches the value checks. Input loads or
// throws InputError.
#include "core/error.h"
#include "io/checkpoint_file.h"
#include "render/checkpoint.h"

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::filesystem::path file =
      std::filesystem::temp_directory_path() / ("kozu-fuzz-checkpoint-" + std::to_string(getpid()) + ".ckpt");
  {
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    const kozu::CheckpointFileReader reader(file);
    const kozu::RenderIdentity id = kozu::checkpoint_identity(reader.header(), file);
    // A render's window is within --resolution's range; the payload's length is checked against it.
    if (id.window_size.x >= 1 && id.window_size.y >= 1 && id.window_size.x <= 65536 && id.window_size.y <= 65536)
      kozu::load_checkpoint(file, id);
  } catch (const kozu::InputError&) {
  }
  std::filesystem::remove(file);
  return 0;
}
