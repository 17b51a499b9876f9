// `kozu merge PART.exr... -o OUT.exr`: combines the EXRs of renders of one scene split across machines, by pixels
// (`--crop`) or by samples (`--sample-range`), into the image one render of all their samples gives. Each pixel
// is the sample-count-weighted mean of the parts that hold it (counts from each part's sample_count channel, or
// its kozu:spp_* attributes when it finished evenly). Crops paste exactly; sample ranges agree with one render to
// float rounding (the parts store means, not sums). Exit codes: 0 success, 1 bad input or failure to write.
#include "apps/commands.h"
#include "core/error.h"
#include "core/file_io.h"
#include "core/memory.h"
#include "core/tonemap.h"
#include "io/image_io.h"
#include "render/output_paths.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <string>

namespace kozu::app {

namespace {

struct Part {
  std::string file;
  Image image;
  std::map<std::string, std::string> attributes;
  int count_channel = -1;      // index of sample_count, or -1
  uint32_t uniform_count = 0;  // samples of every pixel when there is no count channel
  int64_t sample_begin = 0;
  int64_t sample_end = 0;  // begin + the most samples of a pixel
};

std::string attribute(const Part& p, const std::string& name) {
  const auto it = p.attributes.find(name);
  if (it == p.attributes.end())
    throw InputError(p.file, "",
                     fmt::format("not a kozu render: no {} attribute (kozu merge combines kozu EXRs)", name));
  return it->second;
}

// A part's header (no pixels: p.image.data stays empty), with every check that needs no pixel.
Part read_part_header(const std::string& file) {
  Part p;
  p.file = file;
  if (lower_extension(file) != ".exr") throw InputError(file, "", "kozu merge reads EXR parts only");
  p.image = read_image_header(file);
  for (const auto& [k, v] : p.image.attributes) p.attributes[k] = v;
  if (p.image.channels < 3 || p.image.channel_names[0] != "R" || p.image.channel_names[1] != "G" ||
      p.image.channel_names[2] != "B")
    throw InputError(file, "", "the first channels are not R, G, B");
  for (int c = 0; c < p.image.channels; ++c)
    if (p.image.channel_names[c] == "sample_count") p.count_channel = c;
  // The part must lie inside its display window, which bounds the merged image (and its memory).
  const Vec2i full = p.image.full_size, o = p.image.origin;
  if (full.x <= 0 || full.y <= 0 || uint64_t(full.x) * uint64_t(full.y) > kMaxImagePixels)
    throw InputError(file, "", fmt::format("display window {}x{} is empty or too large", full.x, full.y));
  if (o.x < 0 || o.y < 0 || o.x > full.x - p.image.width || o.y > full.y - p.image.height)
    throw InputError(file, "",
                     fmt::format("its {}x{} pixels at {},{} lie outside its {}x{} display window", p.image.width,
                                 p.image.height, o.x, o.y, full.x, full.y));
  try {
    p.sample_begin = std::stoll(attribute(p, "kozu:sample_begin"));
    const uint32_t lo = static_cast<uint32_t>(std::stoul(attribute(p, "kozu:spp_min")));
    const uint32_t hi = static_cast<uint32_t>(std::stoul(attribute(p, "kozu:spp_max")));
    p.sample_end = p.sample_begin + hi;
    if (p.count_channel < 0) {
      if (lo != hi)
        throw InputError(file, "",
                         fmt::format("its pixels hold {} to {} samples and it has no sample_count channel, so it "
                                     "cannot be weighed (render parts with --sample-range or --crop)",
                                     lo, hi));
      p.uniform_count = hi;
    }
  } catch (const InputError&) {
    throw;
  } catch (const std::exception&) {
    throw InputError(file, "", "malformed kozu:sample_begin or kozu:spp_* attribute");
  }
  if (attribute(p, "kozu:partial") == "1")
    std::fprintf(stderr, "warning: %s is a partial image (written while rendering); merged as it is\n", file.c_str());
  return p;
}

// The parts must be of one render: same scene, seed, image size and channels; parts over the same pixels must hold
// different samples. Throws InputError naming the part.
void check_parts_agree(const std::vector<Part>& parts) {
  const Part& first = parts.front();
  for (const Part& p : parts) {
    for (const char* key : {"kozu:scene_hash", "kozu:seed", "kozu:version"})
      if (attribute(p, key) != attribute(first, key))
        throw InputError(p.file, "",
                         fmt::format("its {} is {}, but {} has {}: parts of different renders", key, attribute(p, key),
                                     first.file, attribute(first, key)));
    if (p.image.full_size != first.image.full_size)
      throw InputError(p.file, "",
                       fmt::format("it is part of a {}x{} image, {} of a {}x{} one", p.image.full_size.x,
                                   p.image.full_size.y, first.file, first.image.full_size.x, first.image.full_size.y));
    if (p.image.channel_names != first.image.channel_names)
      throw InputError(p.file, "", fmt::format("its channels differ from {}'s", first.file));
  }
  // Parts over the same pixels must hold different samples.
  for (size_t a = 0; a < parts.size(); ++a)
    for (size_t b = a + 1; b < parts.size(); ++b) {
      const Part &p = parts[a], &q = parts[b];
      const Vec2i lo = glm::max(p.image.origin, q.image.origin);
      const Vec2i hi = glm::min(p.image.origin + Vec2i(p.image.width, p.image.height),
                                q.image.origin + Vec2i(q.image.width, q.image.height));
      const bool share_pixels = lo.x < hi.x && lo.y < hi.y;
      const bool share_samples = p.sample_begin < q.sample_end && q.sample_begin < p.sample_end;
      if (share_pixels && share_samples)
        throw InputError(q.file, "",
                         fmt::format("it holds samples {}..{} of pixels that {} holds samples {}..{} of: the same "
                                     "samples would count twice",
                                     q.sample_begin, q.sample_end - 1, p.file, p.sample_begin, p.sample_end - 1));
    }
}

// The merged image's window: the parts' bounding box, which they must be able to cover and which must fit in memory.
struct MergeWindow {
  Vec2i lo, size;
  size_t n = 0;  // pixels
};
MergeWindow merge_window(const std::vector<Part>& parts, const std::string& first_input) {
  const Part& first = parts.front();
  Vec2i lo = first.image.origin, hi = lo;
  for (const Part& p : parts) {
    lo = glm::min(lo, p.image.origin);
    hi = glm::max(hi, p.image.origin + Vec2i(p.image.width, p.image.height));
  }
  const Vec2i size = hi - lo;
  const int channels = first.image.channels;
  const size_t n = static_cast<size_t>(size.x) * size.y;
  // Every pixel of the bounding box needs a part that holds it: parts holding fewer pixels in all cannot cover it
  // (two 1x1 parts at opposite corners of a 16384^2 display window would otherwise allocate gigabytes first).
  uint64_t part_pixels = 0, part_bytes = 0;
  for (const Part& p : parts) {
    part_pixels += uint64_t(p.image.width) * uint64_t(p.image.height);
    part_bytes += image_bytes(p.image);
  }
  if (part_pixels < n)
    throw InputError(first_input, "",
                     fmt::format("the parts hold {} pixels in all, fewer than the {} of the merged window {}x{} at "
                                 "{},{} (a crop or a sample range is missing)",
                                 part_pixels, n, size.x, size.y, lo.x, lo.y));
  // The memory: the parts' pixels, the merged sums and counts (doubles), its float image and extra channels, and
  // the EXR writer's interleaved copy.
  const uint64_t need =
      uint64_t(n) * (uint64_t(channels) * 8 + 8 + 12 + uint64_t(channels - 3) * 4 + uint64_t(channels) * 4) +
      part_bytes;
  const MemoryLimit limit = memory_limit();
  if (double(need) > memory_left(limit))
    throw InputError(first_input, "",
                     fmt::format("merging {} parts into {}x{} pixels of {} channels needs {}, more than is left of "
                                 "the {} memory limit ({})",
                                 parts.size(), size.x, size.y, channels, format_bytes(double(need)),
                                 format_bytes(double(limit.bytes)), limit.source));
  return {lo, size, n};
}

// Every part's samples summed into the window: `sums` holds channels per pixel (weighted by the part's sample
// counts), `counts` the samples per pixel.
void accumulate_parts(std::vector<Part>& parts, const MergeWindow& window, int channels, int alpha_channel,
                      std::vector<double>& sums, std::vector<double>& counts) {
  // Every part's pixels are read (and so proven whole) before the merged window is allocated; each file must still
  // be the one whose header was checked.
  for (Part& p : parts) {
    Image im = read_image_all(p.file);
    if (im.width != p.image.width || im.height != p.image.height || im.channel_names != p.image.channel_names ||
        im.origin != p.image.origin || im.full_size != p.image.full_size)
      throw InputError(p.file, "", "the file changed while kozu merge read it");
    p.image = std::move(im);
  }
  sums.assign(window.n * channels, 0.0);
  counts.assign(window.n, 0.0);
  for (Part& p : parts) {
    const Image& im = p.image;
    for (int y = 0; y < im.height; ++y)
      for (int x = 0; x < im.width; ++x) {
        const float* v = &im.data[(static_cast<size_t>(y) * im.width + x) * channels];
        const double w = p.count_channel >= 0 ? v[p.count_channel] : p.uniform_count;
        if (!(w >= 0.0))
          throw InputError(p.file, "",
                           fmt::format("pixel ({}, {}) has a sample count of {}", x + im.origin.x, y + im.origin.y, w));
        const size_t o =
            static_cast<size_t>(y + im.origin.y - window.lo.y) * window.size.x + (x + im.origin.x - window.lo.x);
        counts[o] += w;
        for (int c = 0; c < channels; ++c)
          sums[o * channels + c] += c == p.count_channel ? v[c] : c == alpha_channel ? std::round(w * v[c]) : w * v[c];
      }
    p.image.data = std::vector<float>();  // freed once added
  }
}

int run_merge(const std::vector<std::string>& inputs, const std::vector<std::string>& outputs,
              const std::string& tonemap_name, bool keep_negative) {
  ToneMap tonemap;
  tonemap.curve = ToneMap::parse(tonemap_name);
  // Every output is checked before any work; the parts are inputs, which no output may replace.
  {
    std::vector<OutputFile> files;
    for (const auto& out : outputs) files.push_back(OutputFile{out, "-o", true});
    check_outputs(files, std::vector<std::filesystem::path>(inputs.begin(), inputs.end()));
  }
  // Headers first: every part's windows, channels and attributes are checked, and the memory of the merge, before
  // any pixel buffer is allocated.
  std::vector<Part> parts;
  for (const auto& f : inputs) parts.push_back(read_part_header(f));
  const Part& first = parts.front();
  check_parts_agree(parts);
  // The merged image covers the parts' bounding box.
  const MergeWindow window = merge_window(parts, inputs.front());
  const Vec2i lo = window.lo, size = window.size;
  const size_t n = window.n;
  const int channels = first.image.channels;
  // Alpha (--alpha) is hits / count of integers: alpha x count rounds back to the part's hits exactly (both below
  // 2^24), so the merged alpha is the whole render's bit for bit.
  const auto a_it = std::find(first.image.channel_names.begin(), first.image.channel_names.end(), "A");
  const int alpha_channel =
      a_it == first.image.channel_names.end() ? -1 : static_cast<int>(a_it - first.image.channel_names.begin());
  std::vector<double> sums, counts;
  accumulate_parts(parts, window, channels, alpha_channel, sums, counts);
  const size_t empty = static_cast<size_t>(std::count(counts.begin(), counts.end(), 0.0));
  if (empty > 0)
    throw InputError(inputs.front(), "",
                     fmt::format("{} of the {} pixels of the merged window {}x{} at {},{} have no sample in any part "
                                 "(a crop or a sample range is missing)",
                                 empty, n, size.x, size.y, lo.x, lo.y));
  std::vector<float> rgb(n * 3);
  ImageExtras extras;
  extras.origin = lo;
  extras.full_size = first.image.full_size;
  extras.channels.assign(first.image.channel_names.begin() + 3, first.image.channel_names.end());
  extras.data.resize(n * (channels - 3));
  double spp_sum = 0, spp_min = 1e300, spp_max = 0;
  for (size_t i = 0; i < n; ++i) {
    for (int c = 0; c < channels; ++c) {
      const double v = c == first.count_channel ? sums[i * channels + c] : sums[i * channels + c] / counts[i];
      (c < 3 ? rgb[i * 3 + c] : extras.data[i * (channels - 3) + (c - 3)]) = static_cast<float>(v);
    }
    spp_sum += counts[i];
    spp_min = std::min(spp_min, counts[i]);
    spp_max = std::max(spp_max, counts[i]);
  }
  // The renders' "negative_pixels" (render_settings.h): the merged image is a final one, whose pixels below 0 are 0
  // where any part's render said "clamp" (its --sample-range parts kept them signed for this sum), unless
  // --keep-negative asks for the signed means (a merge of ranges that a later merge adds to). Parts without the
  // attribute (kozu before it) kept them.
  const bool clamp = !keep_negative && std::any_of(parts.begin(), parts.end(), [](const Part& p) {
    const auto it = p.attributes.find("kozu:negative_pixels");
    return it != p.attributes.end() && it->second == "clamp";
  });
  if (clamp)
    for (float& v : rgb) v = std::max(v, 0.0f);
  int64_t begin = first.sample_begin;
  for (const Part& p : parts) begin = std::min(begin, p.sample_begin);
  extras.attributes = {{"kozu:version", attribute(first, "kozu:version")},
                       {"kozu:scene_hash", attribute(first, "kozu:scene_hash")},
                       {"kozu:seed", attribute(first, "kozu:seed")},
                       {"kozu:sample_begin", std::to_string(begin)},
                       {"kozu:spp_mean", fmt::format("{}", spp_sum / static_cast<double>(n))},
                       {"kozu:spp_min", fmt::format("{:.0f}", spp_min)},
                       {"kozu:spp_max", fmt::format("{:.0f}", spp_max)},
                       {"kozu:partial", "0"},
                       {"kozu:merged_parts", std::to_string(parts.size())},
                       {"kozu:negative_pixels", clamp ? "clamp" : "keep"}};
  extras.matrices = first.image.matrices;  // the camera's (worldToCamera, worldToNDC): the parts share it
  // A merged image without a count channel still weighs right in a later merge only if its counts are even.
  if (first.count_channel < 0 && spp_min != spp_max)
    std::fprintf(stderr, "warning: the merged pixels hold %.0f to %.0f samples and there is no sample_count channel\n",
                 spp_min, spp_max);
  std::string written;
  for (const auto& out : outputs) {
    write_image(out, size.x, size.y, rgb, tonemap, extras);
    written += (written.empty() ? "" : ", ") + out;
  }
  std::fprintf(stderr, "kozu merge: %zu parts, %dx%d at %d,%d of %dx%d, %.1f spp, wrote %s\n", parts.size(), size.x,
               size.y, lo.x, lo.y, first.image.full_size.x, first.image.full_size.y, spp_sum / static_cast<double>(n),
               written.c_str());
  return 0;
}

}  // namespace

Command add_merge_command(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "merge", "Combine the EXRs of one render split by --crop or --sample-range into the whole render's image");
  auto inputs = std::make_shared<std::vector<std::string>>();
  auto outputs = std::make_shared<std::vector<std::string>>();
  auto tonemap = std::make_shared<std::string>("aces");
  cmd->add_option("parts", *inputs, "The parts: EXRs written by kozu render")->required();
  cmd->add_option("-o,--output", *outputs, "Merged image (.exr keeps every channel; .png/.jpg are tone-mapped)")
      ->required();
  cmd->add_option("--tonemap", *tonemap, "Display transform for .png/.jpg: aces, neutral, agx or clamp")
      ->capture_default_str();
  auto keep_negative = std::make_shared<bool>(false);
  cmd->add_flag("--keep-negative", *keep_negative,
                "Keep pixels below 0 signed (for a merge of sample ranges that a later merge adds to); by default "
                "they are 0 where the render's render.negative_pixels is \"clamp\"");
  return [cmd, inputs, outputs, tonemap, keep_negative]() -> int {
    if (!cmd->parsed()) return 2;
    try {
      return run_merge(*inputs, *outputs, *tonemap, *keep_negative);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "error: kozu merge: %s\n", e.what());
      return 1;
    }
  };
}

}  // namespace kozu::app
