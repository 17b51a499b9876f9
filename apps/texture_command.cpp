// `kozu texture ...`: a group of texture tools, each a subcommand of its own.
//   filter-normals  normal and gloss mip filtering by shortened normals (textures/normal_gloss_filter.h)
//   height, occlusion  apps/texture_height_command.cpp
// Exit codes: 0 success, 1 bad input or failure to write, 2 usage errors (kozu.cpp).
#include "apps/command_errors.h"
#include "apps/commands.h"
#include "core/file_io.h"
#include "render/output_paths.h"
#include "textures/normal_gloss_files.h"

#include <chrono>
#include <cstdio>

#include <fmt/format.h>

#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace kozu::app {
namespace {

// `kozu texture filter-normals NORMAL [--gloss GLOSS | --gloss-value G] -o OUT_NORMAL OUT_GLOSS [--model macro|micro]`
Command add_filter_normals_command(CLI::App& group) {
  CLI::App* cmd = group.add_subcommand(
      "filter-normals",
      "Mip-map a normal map and its gloss together (Chan 2018 §2): bumps too small for a level become its gloss");
  auto normal = std::make_shared<std::string>();
  auto gloss = std::make_shared<std::string>();
  auto gloss_value = std::make_shared<double>(1.0);
  auto outputs = std::make_shared<std::vector<std::string>>();
  auto model = std::make_shared<std::string>("macro");
  cmd->add_option("normal", *normal, "Tangent-space normal map (OpenGL convention, n = 2 c - 1)")->required();
  CLI::Option* g = cmd->add_option("--gloss", *gloss, "Gloss map (first channel, in [0, 1]), the normal map's size");
  CLI::Option* gv =
      cmd->add_option("--gloss-value", *gloss_value, "One gloss for every texel, in [0, 1]")->capture_default_str();
  g->excludes(gv);
  cmd->add_option("-o,--output", *outputs, "The normal and gloss mip chains: OUT_NORMAL OUT_GLOSS (.exr, .tx, .tif)")
      ->required()
      ->expected(2);
  // Checked by the command: a bad value is bad input (exit 1), not a usage error.
  cmd->add_option("--model", *model, "Shortened-normal model: macro (Algorithm 2, default) or micro (Algorithm 1)")
      ->capture_default_str();
  return [cmd, normal, gloss, gloss_value, outputs, model]() -> int {
    if (!cmd->parsed()) return 2;
    try {
      NormalGlossFilterJob job;
      if (*model == "macro")
        job.model = ShortenedNormalModel::Macro;
      else if (*model == "micro")
        job.model = ShortenedNormalModel::Micro;
      else
        throw std::runtime_error(fmt::format("--model: '{}' is not one of macro, micro", *model));
      if (!(*gloss_value >= 0.0 && *gloss_value <= 1.0))
        throw std::runtime_error(fmt::format("--gloss-value: expected a number in [0, 1], got {}", *gloss_value));
      for (const std::string& out : *outputs) {
        const std::string ext = lower_extension(out);
        if (ext != ".exr" && ext != ".tx" && ext != ".tif" && ext != ".tiff")
          throw std::runtime_error(fmt::format("-o: {}: the outputs are .exr, .tx or .tif files", out));
      }
      job.normal_map = *normal;
      job.gloss_map = *gloss;
      job.gloss_value = *gloss_value;
      job.out_normal = (*outputs)[0];
      job.out_gloss = (*outputs)[1];
      std::vector<std::filesystem::path> inputs = {job.normal_map};
      if (!gloss->empty()) inputs.push_back(job.gloss_map);
      check_outputs(
          {OutputFile{job.out_normal, "-o", false, false, false}, OutputFile{job.out_gloss, "-o", false, false, false}},
          inputs);
      const auto start = std::chrono::steady_clock::now();
      const NormalGlossFilterSummary s = filter_normal_gloss_files(job);
      std::fprintf(stderr,
                   "%s, %s: %d x %d, %d mip levels (%s model); gloss %.4f (mean, level 0) -> %.4f (1 x 1) in "
                   "%.2f s\n",
                   job.out_normal.string().c_str(), job.out_gloss.string().c_str(), s.width, s.height, s.levels,
                   model->c_str(), s.mean_gloss_level0, s.mean_gloss_last,
                   std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    } catch (const std::exception& e) {
      return report_failure("texture filter-normals", e);
    }
    return 0;
  };
}

}  // namespace

Command add_texture_command(CLI::App& app) {
  CLI::App* group = app.add_subcommand("texture", "Texture tools: filter-normals, height, occlusion");
  group->require_subcommand(1);
  auto run = std::make_shared<std::vector<std::pair<std::string, Command>>>();
  run->emplace_back("filter-normals", add_filter_normals_command(*group));
  add_texture_height_commands(*group, *run);
  return [group, run]() -> int {
    for (const auto& [name, command] : *run)
      if (group->got_subcommand(name)) return command();
    return 2;
  };
}

}  // namespace kozu::app
