// Reading whole input files, and writing output files atomically, with messages that name the file and the reason.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>

namespace kozu {

// The file's bytes. Throws InputError(file, "", "cannot open file: <reason>") or a read error.
std::string read_input_file(const std::filesystem::path& file);
// The file opened for binary reading, with the same messages when it cannot be (a directory, missing,
// unreadable).
std::ifstream open_input_file(const std::filesystem::path& file);

// Writes content to a temporary file beside `file`, then renames it into place, so a reader never sees a
// half-written file. Throws std::runtime_error naming the file.
void write_file_atomic(const std::filesystem::path& file, const std::string& content);

// The file's extension in lower case, with its dot (".exr"; "" if none): formats are chosen by it.
std::string lower_extension(const std::filesystem::path& file);

}  // namespace kozu
