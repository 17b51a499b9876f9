#include "io/file_io.h"

#include "core/error.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <system_error>

namespace kozu {

std::ifstream open_input_file(const std::filesystem::path& file) {
  auto fail = [&](const std::string& message) { throw InputError(file.string(), "", message); };
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec)) fail("cannot open file: it is a directory");
  errno = 0;
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    const int err = errno;
    // std::generic_category rather than strerror: loaders run in parallel threads.
    fail("cannot open file: " + (err ? std::generic_category().message(err) : std::string("unknown error")));
  }
  return in;
}

std::string read_input_file(const std::filesystem::path& file) {
  auto fail = [&](const std::string& message) { throw InputError(file.string(), "", message); };
  std::ifstream in = open_input_file(file);
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  in.seekg(0, std::ios::beg);
  if (size < 0 || !in) fail("cannot determine the file size");
  std::string data(static_cast<size_t>(size), '\0');
  in.read(data.data(), size);
  if (in.gcount() != size) fail("read error: file ended early or could not be read");
  return data;
}

void write_file_atomic(const std::filesystem::path& file, const std::string& content) {
  const std::filesystem::path tmp = file.string() + fmt::format(".{}.tmp", static_cast<long>(getpid()));
  {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw std::runtime_error(fmt::format("{}: cannot write: {}", file.string(), std::strerror(errno)));
    out << content;
    if (!out) throw std::runtime_error(fmt::format("{}: write failed", file.string()));
  }
  std::error_code ec;
  std::filesystem::rename(tmp, file, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw std::runtime_error(fmt::format("{}: cannot move into place: {}", file.string(), ec.message()));
  }
}

std::string lower_extension(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

}  // namespace kozu
