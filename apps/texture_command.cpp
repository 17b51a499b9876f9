// `kozu texture ...`: a group of texture tools, each a subcommand of its own.
//   filter-normals  normal and gloss mip filtering by shortened normals (textures/normal_gloss_filter.h)
//   height, occlusion  apps/texture_height_command.cpp
// Exit codes: 0 success, 1 bad input or failure to write, 2 usage errors (kozu.cpp).
#include "apps/commands.h"

#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace kozu::app {

Command add_texture_command(CLI::App& app) {
  CLI::App* group = app.add_subcommand("texture", "Texture tools: filter-normals, height, occlusion");
  group->require_subcommand(1);
  auto run = std::make_shared<std::vector<std::pair<std::string, Command>>>();
  add_texture_height_commands(*group, *run);
  return [group, run]() -> int {
    for (const auto& [name, command] : *run)
      if (group->got_subcommand(name)) return command();
    return 2;
  };
}

}  // namespace kozu::app
