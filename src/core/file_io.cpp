#include "core/file_io.h"

#include "core/error.h"
#include "core/memory.h"
#include "core/temp_files.h"

#include <fmt/format.h>
#include <sys/stat.h>
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
  // A FIFO, a device or a socket could block a read forever or never end (/dev/stdin, /dev/zero).
  const std::filesystem::file_status st = std::filesystem::status(file, ec);
  if (!ec && std::filesystem::exists(st) && !std::filesystem::is_regular_file(st))
    fail("cannot open file: not a regular file (a device, FIFO or socket)");
  errno = 0;
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    const int err = errno;
    // std::generic_category rather than strerror: loaders run in parallel threads. A file that is there but
    // cannot be opened (permissions) is not "not found": its own words.
    fail((err == ENOENT || err == ENOTDIR ? "cannot open file: " : "cannot be read: ") + errno_message(err));
  }
  return in;
}

std::string read_input_file(const std::filesystem::path& file, uint64_t max_bytes) {
  auto fail = [&](const std::string& message) { throw InputError(file.string(), "", message); };
  std::ifstream in = open_input_file(file);
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  in.seekg(0, std::ios::beg);
  if (size < 0 || !in) fail("cannot determine the file size");
  if (static_cast<uint64_t>(size) > max_bytes)
    fail(fmt::format("the file is {}; kozu reads at most {} from one input file", format_bytes(double(size)),
                     format_bytes(double(max_bytes))));
  const MemoryLimit limit = memory_limit();
  if (double(size) > memory_left(limit))
    fail(fmt::format("the file is {}, more than is left of the {} memory limit ({})", format_bytes(double(size)),
                     format_bytes(double(limit.bytes)), limit.source));
  std::string data(static_cast<size_t>(size), '\0');
  in.read(data.data(), size);
  if (in.gcount() != size) fail("read error: file ended early or could not be read");
  return data;
}

std::filesystem::path temp_path_for(const std::filesystem::path& file) {
  return file.parent_path() /
         fmt::format(".{}.{}.tmp{}", file.stem().string(), static_cast<long>(getpid()), file.extension().string());
}

void write_file_atomic(const std::filesystem::path& file, const std::string& content) {
  TempFileGuard tmp(temp_path_for(file));
  {
    errno = 0;
    std::ofstream out;
    create_temp_file([&] { out.open(tmp.path(), std::ios::binary); });
    if (!out) throw std::runtime_error(fmt::format("{}: cannot write: {}", file.string(), errno_message(errno)));
    out << content;
    out.flush();
    if (!out) throw std::runtime_error(fmt::format("{}: write failed: {}", file.string(), errno_message(errno)));
  }
  rename_into_place(tmp, file);
}

void rename_into_place(TempFileGuard& tmp, const std::filesystem::path& file) {
  // rename() replaces whatever the name is: a FIFO or a device node made after the outputs were checked would
  // become a regular file. (A narrow race remains between this test and the rename; POSIX offers no rename that
  // refuses a special file.)
  if (const std::string kind = special_file_kind(file); !kind.empty())
    throw std::runtime_error(fmt::format("{}: is {}, not a regular file; not replaced", file.string(), kind));
  std::error_code ec;
  std::filesystem::rename(tmp.path(), file, ec);
  // The guard removes the temporary file; the message keeps rename's own error.
  if (ec) throw std::runtime_error(fmt::format("{}: cannot move into place: {}", file.string(), ec.message()));
  tmp.release();
}

std::string special_file_kind(const std::filesystem::path& file) {
  const auto kind = [](const struct stat& st) -> std::string {
    if (S_ISREG(st.st_mode) || S_ISDIR(st.st_mode)) return "";
    if (S_ISFIFO(st.st_mode)) return "a FIFO";
    if (S_ISCHR(st.st_mode)) return "a character device";
    if (S_ISBLK(st.st_mode)) return "a block device";
    if (S_ISSOCK(st.st_mode)) return "a socket";
    return "a special file";
  };
  struct stat st {};
  if (::lstat(file.c_str(), &st) != 0) return "";  // missing (or unreachable: the write itself will say why)
  if (!S_ISLNK(st.st_mode)) return kind(st);
  // A link is replaced by the rename, not followed, but a link to a device names the device as the output.
  if (::stat(file.c_str(), &st) != 0) return "";  // a dangling link
  const std::string target = kind(st);
  return target.empty() ? "" : "a symbolic link to " + target;
}

std::string errno_message(int err) { return err ? std::generic_category().message(err) : std::string("unknown error"); }

std::string lower_extension(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

}  // namespace kozu
