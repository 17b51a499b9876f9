// Reading whole input files, and writing output files atomically, with messages that name the file and the reason.
#pragma once

#include "core/temp_files.h"

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace kozu {

// The largest input file kozu reads whole (scenes, meshes, .kvox grids): 8 GiB.
inline constexpr uint64_t kMaxInputFileBytes = uint64_t{8} << 30;

// The file's bytes. Throws InputError(file, "", "cannot open file: <reason>"), a read error, or a size error
// when the file is larger than max_bytes or than the memory left (checked before allocating).
std::string read_input_file(const std::filesystem::path& file, uint64_t max_bytes = kMaxInputFileBytes);
// The file opened for binary reading, with the same messages when it cannot be (a directory, a device, FIFO or
// socket, missing, unreadable).
std::ifstream open_input_file(const std::filesystem::path& file);

// Writes content to a temporary file beside `file`, then renames it into place, so a reader never sees a
// half-written file. Throws std::runtime_error naming the file; the temporary file never outlives the call.
void write_file_atomic(const std::filesystem::path& file, const std::string& content);
// The temporary file `file` is written to before it is renamed into place: hidden, in the same folder (so the
// rename is atomic), with the same extension (image writers are chosen by it): "dir/.name.<pid>.tmp.ext".
std::filesystem::path temp_path_for(const std::filesystem::path& file);

// Renames a finished temporary file onto `file` and releases it; throws std::runtime_error with rename's error
// (the guard then removes the temporary file). An existing `file` that is not a regular file (a FIFO, a device,
// a socket, or a symbolic link to one) is refused, never replaced: outputs are checked before any work, and this
// check holds for one made between that check and the write.
void rename_into_place(TempFileGuard& tmp, const std::filesystem::path& file);

// What an existing path is when it is not a regular file ("a FIFO", "a character device", "a symbolic link to a
// block device", ...), or "" for a regular file, a folder or a path that does not exist: an output may replace
// only a regular file.
std::string special_file_kind(const std::filesystem::path& file);

// The message of an errno value; thread-safe, unlike strerror.
std::string errno_message(int err);

// The file's extension in lower case, with its dot (".exr"; "" if none): formats are chosen by it.
std::string lower_extension(const std::filesystem::path& file);

}  // namespace kozu
