// `kozu fit-rational DATA.csv --num N --den M [--constraint X=Y ...] [--2d-symmetric] --json OUT.json` (in progress).
#include "apps/commands.h"

namespace kozu::app {

Command add_fit_rational_command(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("fit-rational", "Fit a rational function P/Q to a table (Chan 2018 §3)");
  return [cmd]() -> int { return cmd->parsed() ? 1 : 2; };
}

}  // namespace kozu::app
