// Subcommands of the kozu executable. Each registers its options on the CLI11 app and returns the
// exit code of its run: 0 success, 1 bad input or failure to write output.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>

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
Command add_merge_command(CLI::App& app);

}  // namespace kozu::app
