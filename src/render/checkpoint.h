// Checkpoints of a render (`kozu render --checkpoint FILE`, `--resume FILE`): the film's exact accumulators and the
// identity of the render they belong to. A resumed render continues each pixel at its next sample index, so its
// image is bit-identical to the render never stopped (render/renderer.h); a checkpoint of another scene, another
// seed or setting that changes the samples, or another kozu version is refused, naming the difference.
#pragma once

#include "render/film.h"

#include <filesystem>
#include <optional>
#include <string>

namespace kozu {

// What must match for a film's samples to be continued: everything that changes a sample's value.
struct RenderIdentity {
  std::string kozu_version;
  uint64_t scene_hash = 0;  // the scene file's bytes, and each input file's name and size
  uint64_t seed = 0;
  int max_depth = 0;
  std::string direct;  // "sample", "ltc", ...
  std::string filter;  // pixel filter
  Vec2i resolution{0};
  Vec2i window_origin{0}, window_size{0};  // the film's window (--crop)
  int sample_begin = 0;                    // --sample-range's first index
  bool features = false;                   // the film keeps features (AOVs): stored after the pixels
  bool positions = false;                  // and position sums (--aov position): stored after the features
  bool alpha = false;                      // the film keeps coverage counts (--alpha): stored after those

  nlohmann::json to_json() const;
  // The first difference from `other`, as "seed 3 (this render: 4)"; nullopt when they match. A checkpoint that
  // keeps positions this render does not need matches (they are dropped on loading).
  std::optional<std::string> difference(const RenderIdentity& checkpoint) const;
};

// The identity a checkpoint's header records; InputError when a field is missing or has a wrong type.
RenderIdentity checkpoint_identity(const nlohmann::json& header, const std::filesystem::path& file);

// Writes film and identity atomically.
void save_checkpoint(const std::filesystem::path& file, const RenderIdentity& identity, const Film& film);
// The film stored in `file`; InputError when the file is not a whole checkpoint or belongs to another render than
// `expected`.
Film load_checkpoint(const std::filesystem::path& file, const RenderIdentity& expected);

}  // namespace kozu
