// `kozu texture height` and `kozu texture occlusion`: registered here into the `texture` group
// (apps/texture_command.cpp). Stub: no subcommands yet; the engineer who owns them replaces this body.
#include "apps/commands.h"

namespace kozu::app {

void add_texture_height_commands(CLI::App& /*texture*/, std::vector<std::pair<std::string, Command>>& /*run*/) {}

}  // namespace kozu::app
