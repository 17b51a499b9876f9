// The outputs of a render job's frames (render/job.h): frame-number patterns in output names ("%04d", printf's) and
// the checks of every frame's names before the first frame is rendered.
#pragma once

#include "core/math.h"
#include "render/output_paths.h"

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace kozu::render_job {

// The first "%d" or "%0Nd" in `s`: [begin, end) of it.
std::optional<std::pair<size_t, size_t>> find_frame_pattern(const std::string& s);
bool has_frame_pattern(const std::string& s);
// `s` with its frame pattern replaced by `frame` ("out/%04d.png", 7 -> "out/0007.png"); `s` itself without one.
std::string frame_path(const std::string& s, int frame);

// What is already under the names a numbered output takes for frames A..B: a folder, a FIFO, a device or an input of
// the render is refused, naming the frame (throws std::runtime_error).
void check_numbered_output(const OutputFile& o, Vec2i frames, const std::vector<std::filesystem::path>& inputs);

// "--frames A:B" (both included) or "--frames N" of an animation of `count` frames; throws InputError.
Vec2i frames_flag(const std::string& text, int count);

}  // namespace kozu::render_job
