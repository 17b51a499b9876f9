#include "render/output_paths.h"

#include "core/file_io.h"
#include "core/temp_files.h"
#include "io/image_io.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <stdexcept>
#include <system_error>

namespace kozu {

namespace {

// The same file: equivalent() where the output exists, else the same normalised absolute path.
bool same_file(const std::filesystem::path& a, const std::filesystem::path& b) {
  std::error_code ec;
  if (std::filesystem::exists(a, ec) && std::filesystem::exists(b, ec)) return std::filesystem::equivalent(a, b, ec);
  return std::filesystem::weakly_canonical(a, ec) == std::filesystem::weakly_canonical(b, ec);
}

// Creates the output's folder if needed (create_folder) and proves the output's temporary file can be made in it (then
// removes it): permissions, read-only file systems, missing parents and over-long names all show here, not after the
// render.
void check_writable_folder(const OutputFile& out) {
  const auto fail = [&](const std::string& why) {
    throw std::runtime_error(fmt::format("{} {}: cannot be written: {}", out.flag, out.path.string(), why));
  };
  std::filesystem::path dir = out.path.parent_path();
  if (dir.empty()) dir = ".";
  std::error_code ec;
  if (out.create_folder) {
    std::filesystem::create_directories(dir, ec);
    if (ec) fail(fmt::format("cannot create the folder {}: {}", dir.string(), ec.message()));
  } else if (!std::filesystem::exists(dir, ec)) {
    fail(fmt::format("the folder {} does not exist", dir.string()));
  }
  if (!std::filesystem::is_directory(dir, ec)) fail(fmt::format("{} is not a folder", dir.string()));
  // The probe is the very temporary file the writer will use, so its name's length is checked too.
  // Registered before it exists, so a second stop signal removes it too; made inside a creation window, so that a
  // stop that ends the process meanwhile removes it too (core/temp_files.h).
  const TempFileGuard probe(temp_path_for(out.path));
  const int fd =
      create_temp_file([&] { return ::open(probe.path().c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600); });
  if (fd < 0) fail(fmt::format("cannot create a file in {}: {}", dir.string(), errno_message(errno)));
  ::close(fd);
}

}  // namespace

void check_outputs(const std::vector<OutputFile>& outputs, const std::vector<std::filesystem::path>& inputs) {
  for (size_t i = 0; i < outputs.size(); ++i) {
    const OutputFile& out = outputs[i];
    const std::string name = out.path.empty() ? out.flag : fmt::format("{} {}", out.flag, out.path.string());
    if (out.image && !is_supported_output(out.path))
      throw std::runtime_error(fmt::format("{}: unsupported output format (use .exr, .hdr, .png or .jpg)", name));
    // "" or "dir/": no file name to write (a name ending in '/' is a folder, existing or not).
    if (out.path.filename().empty())
      throw std::runtime_error(
          fmt::format("{}: {}", name, out.path.empty() ? "an empty file name" : "names a folder, not a file"));
    std::error_code ec;
    if (std::filesystem::is_directory(out.path, ec))
      throw std::runtime_error(fmt::format("{}: is a folder, not a file", name));
    // The writer renames a new file over the name: a device node or a FIFO would be replaced by a regular file
    // (as root, /dev/null itself).
    if (const std::string kind = special_file_kind(out.path); !kind.empty())
      throw std::runtime_error(
          fmt::format("{}: is {}, not a regular file; an output must be a regular file or new", name, kind));
    for (size_t j = 0; j < i; ++j)
      if (same_file(out.path, outputs[j].path))
        throw std::runtime_error(fmt::format("{}: the same file as {} {}; every output needs its own file", name,
                                             outputs[j].flag, outputs[j].path.string()));
    for (const auto& in : inputs)
      if (same_file(out.path, in))
        throw std::runtime_error(fmt::format("{}: would overwrite {}, an input of the render", name, in.string()));
    check_writable_folder(out);
  }
}

void check_output(const std::filesystem::path& path, const std::string& flag,
                  const std::vector<std::filesystem::path>& inputs) {
  check_outputs({OutputFile{path, flag, false, false, false}}, inputs);
}

}  // namespace kozu
