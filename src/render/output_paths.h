// Checks of the files a command will write, made before any work so that a render (or a fit, a grid, a table) is
// never lost to an output that cannot be written, and so that no output destroys what is not a file: each must be a
// supported format (images), a regular file or not yet there (never a folder, a FIFO, a device, a socket or a
// symbolic link to one of those), in a folder that exists or can be created and that takes a new file; none may
// be written twice, and none may be an input of the command. Every command checks all its outputs with these.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace kozu {

struct OutputFile {
  std::filesystem::path path;
  std::string flag;  // "-o" or "--stats", for messages
  bool image = true;
  bool denoised = false;  // takes the denoised image (--denoise)
  // A render creates its output folder (out/); the tool commands write into a folder that exists.
  bool create_folder = true;
};

// Throws std::runtime_error with one message naming the output and the reason. `inputs` are files the render
// reads (the scene and the files it references); an output that is one of them is refused.
void check_outputs(const std::vector<OutputFile>& outputs, const std::vector<std::filesystem::path>& inputs);

// The same checks for a tool command's one output that is not an image (a table, a voxel grid, a profile), whose
// folder must exist: throws std::runtime_error("FLAG PATH: reason").
void check_output(const std::filesystem::path& path, const std::string& flag,
                  const std::vector<std::filesystem::path>& inputs = {});

}  // namespace kozu
