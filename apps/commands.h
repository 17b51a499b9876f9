// Subcommands of the kozu executable. Each registers its options on the CLI11 app and returns the
// exit code of its run: 0 success, 1 bad input or failure to write output.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace kozu::app {

using Command = std::function<int()>;

// A transform for integer options: decimal only, leading zeros kept decimal ("010" is 10, where CLI11 alone
// would read octal, and "0x10" hexadecimal), as scene files and `kozu render`'s flags read numbers.
CLI::Validator decimal_integer();

Command add_render_command(CLI::App& app);
Command add_precompute_command(CLI::App& app);
Command add_sss_reference_command(CLI::App& app);
Command add_voxelize_command(CLI::App& app);
Command add_procedural_command(CLI::App& app);
Command add_maketx_command(CLI::App& app);
Command add_fit_ltc_command(CLI::App& app);
Command add_fit_rational_command(CLI::App& app);
Command add_cod_diffuse_reference_command(CLI::App& app);
Command add_merge_command(CLI::App& app);
// `kozu texture ...`: the texture tools (apps/texture_command.cpp), a group of subcommands.
Command add_texture_command(CLI::App& app);
// `kozu texture height` and `kozu texture occlusion` (apps/texture_height_command.cpp): each adds its subcommand to
// the `texture` group and appends (its name, its run) to `run`, which the group calls for the one parsed.
void add_texture_height_commands(CLI::App& texture, std::vector<std::pair<std::string, Command>>& run);

}  // namespace kozu::app
