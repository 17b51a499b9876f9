// Checks of the files a render will write, made before any work so that a render is never lost to an output
// that cannot be written: each must be a supported format (images), not a folder, in a folder that exists or
// can be created and that takes a new file, none may be written twice, and none may be an input of the render.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace kozu::app {

struct OutputFile {
  std::filesystem::path path;
  std::string flag;  // "-o" or "--stats", for messages
  bool image = true;
  bool denoised = false;  // takes the denoised image (--denoise)
};

// Throws std::runtime_error with one message naming the output and the reason. `inputs` are files the render
// reads (the scene and the files it references); an output that is one of them is refused.
void check_outputs(const std::vector<OutputFile>& outputs, const std::vector<std::filesystem::path>& inputs);

}  // namespace kozu::app
