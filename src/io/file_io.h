// Reading whole input files with messages that name the file and the reason.
#pragma once

#include <filesystem>
#include <string>

namespace kozu {

// The file's bytes. Throws InputError(file, "", "cannot open file: <reason>") or a read error.
std::string read_input_file(const std::filesystem::path& file);

}  // namespace kozu
