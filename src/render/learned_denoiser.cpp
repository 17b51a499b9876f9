#include "render/learned_denoiser.h"

#include "render/denoise_buffers.h"

#include <fmt/format.h>
#include <omp.h>
#include <oneapi/dnnl/dnnl.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>

namespace kozu {

// The compiled-in weights (generated from data/denoiser/unet-v1.kzw by CMake: learned_denoiser_weights.cpp.in);
// size 0 when the file was not there at configure time.
extern const unsigned char kUnetWeightsBlob[];
extern const std::size_t kUnetWeightsBlobSize;

namespace {

constexpr int kInputs = 9;   // colour, albedo, normal
constexpr int kOutputs = 3;  // colour
constexpr int kMaxChannels = 512;
// Read around each tile's core. A core pixel's output depends on the input within 31 pixels of it: each 3 × 3
// convolution reaches one pixel of its level (1, 2, 4 or 8 image pixels) and each max-pool up to one more, summed
// over the graph on the 8-pixel grid the tiles keep (LearnedDenoiser.ReachIsWithinTheOverlap measures it); 32 keeps
// the tiles' own zero padding out of every core pixel's reach, so the tiling does not show.
constexpr int kOverlap = 32;
constexpr int kGrid = 8;  // three 2 × 2 max-pools

[[noreturn]] void fail(const std::string& what) { throw std::runtime_error("learned denoiser weights: " + what); }

int round_up(int v, int m) { return (v + m - 1) / m * m; }

// Sets OpenMP's thread count (what oneDNN's parallel regions use) for the calling thread, and restores it.
class OmpThreads {
 public:
  explicit OmpThreads(int threads) : previous_(omp_get_max_threads()), set_(threads > 0) {
    if (set_) omp_set_num_threads(threads);
  }
  ~OmpThreads() {
    if (set_) omp_set_num_threads(previous_);
  }
  OmpThreads(const OmpThreads&) = delete;
  OmpThreads& operator=(const OmpThreads&) = delete;

 private:
  int previous_;
  bool set_;
};

// The network for one input tile size (tw × th, multiples of 8): the primitives in the order they run, each with
// its arguments, built once and executed for every tile. Convolutions choose their own layouts (format_tag::any);
// a reorder is inserted wherever one primitive's output layout is not what the next one wants.
class Network {
 public:
  using memory = dnnl::memory;
  using tag = memory::format_tag;

  Network(const UnetWeights& wts, int tw, int th) {
    const auto& L = wts.layers;
    input_ = memory({{1, kInputs, th, tw}, memory::data_type::f32, tag::nchw}, engine_);
    memory x = conv(L[0], input_, tw, th, true);
    const memory skip0 = conv(L[1], x, tw, th, true);
    const memory skip1 = conv(L[2], pool(skip0, L[1].out, tw, th), tw / 2, th / 2, true);
    const memory skip2 = conv(L[3], pool(skip1, L[2].out, tw / 2, th / 2), tw / 4, th / 4, true);
    x = conv(L[4], pool(skip2, L[3].out, tw / 4, th / 4), tw / 8, th / 8, true);
    x = up_conv(L[5], x, skip2, tw / 4, th / 4);
    x = up_conv(L[6], x, skip1, tw / 2, th / 2);
    x = up_conv(L[7], x, skip0, tw, th);
    x = conv(L[8], x, tw, th, false);
    output_ = as(x, {{1, kOutputs, th, tw}, memory::data_type::f32, tag::nchw});
  }

  // The input tile, 9 planes of th × tw (nchw), and the output, 3 planes.
  float* input() { return static_cast<float*>(input_.get_data_handle()); }
  const float* output() const { return static_cast<const float*>(output_.get_data_handle()); }

  void run() {
    for (auto& [p, args] : steps_) p.execute(stream_, args);
    stream_.wait();
  }

 private:
  using Step = std::pair<dnnl::primitive, std::unordered_map<int, memory>>;

  struct Conv {
    dnnl::convolution_forward::primitive_desc pd;
    memory weights, bias;
  };

  static memory::desc any(const memory::dims& dims) { return {dims, memory::data_type::f32, tag::any}; }

  // `m` in layout `d`: m itself, or a reorder's output.
  memory as(const memory& m, const memory::desc& d) {
    if (m.get_desc() == d) return m;
    memory r(d, engine_);
    steps_.push_back({dnnl::reorder(m, r), {{DNNL_ARG_FROM, m}, {DNNL_ARG_TO, r}}});
    return r;
  }

  // A convolution's descriptor for a w × h input, with its weights reordered into its layout (once, here).
  Conv make_conv(const UnetLayer& l, int w, int h, bool relu) {
    const memory::dims src{1, l.in, h, w}, wdims{l.out, l.in, 3, 3}, bdims{l.out}, dst{1, l.out, h, w};
    const dnnl::convolution_forward::desc d(dnnl::prop_kind::forward_inference, dnnl::algorithm::convolution_direct,
                                            any(src), any(wdims), {bdims, memory::data_type::f32, tag::x}, any(dst),
                                            {1, 1}, {1, 1}, {1, 1});
    dnnl::post_ops ops;
    if (relu) ops.append_eltwise(1.0f, dnnl::algorithm::eltwise_relu, 0.0f, 0.0f);
    dnnl::primitive_attr attr;
    attr.set_post_ops(ops);
    Conv c{dnnl::convolution_forward::primitive_desc(d, attr, engine_), {}, {}};
    memory user({wdims, memory::data_type::f32, tag::oihw}, engine_);
    std::memcpy(user.get_data_handle(), l.weights.data(), l.weights.size() * sizeof(float));
    c.weights = memory(c.pd.weights_desc(), engine_);
    dnnl::reorder(user, c.weights).execute(stream_, user, c.weights);
    memory user_bias({bdims, memory::data_type::f32, tag::x}, engine_);
    std::memcpy(user_bias.get_data_handle(), l.bias.data(), l.bias.size() * sizeof(float));
    c.bias = memory(c.pd.bias_desc(), engine_);
    dnnl::reorder(user_bias, c.bias).execute(stream_, user_bias, c.bias);
    stream_.wait();
    return c;
  }

  memory add_conv(const Conv& c, const memory& src) {
    const memory in = as(src, c.pd.src_desc());
    memory out(c.pd.dst_desc(), engine_);
    steps_.push_back(
        {dnnl::convolution_forward(c.pd),
         {{DNNL_ARG_SRC, in}, {DNNL_ARG_WEIGHTS, c.weights}, {DNNL_ARG_BIAS, c.bias}, {DNNL_ARG_DST, out}}});
    return out;
  }

  memory conv(const UnetLayer& l, const memory& src, int w, int h, bool relu) {
    return add_conv(make_conv(l, w, h, relu), src);
  }

  // 2 × 2 max-pool, stride 2, of a w × h input of `ch` channels.
  memory pool(const memory& src, int ch, int w, int h) {
    const dnnl::pooling_forward::desc d(dnnl::prop_kind::forward_inference, dnnl::algorithm::pooling_max,
                                        src.get_desc(), any({1, ch, h / 2, w / 2}), {2, 2}, {2, 2}, {0, 0}, {0, 0});
    const dnnl::pooling_forward::primitive_desc pd(d, engine_);
    memory out(pd.dst_desc(), engine_);
    steps_.push_back({dnnl::pooling_forward(pd), {{DNNL_ARG_SRC, src}, {DNNL_ARG_DST, out}}});
    return out;
  }

  // Nearest-neighbour upsampling of `low` to w × h, concatenated with `skip` ([up, skip] along the channels), then
  // convolution l with ReLU. The concatenation writes straight into the convolution's input layout where oneDNN can
  // (a blocked layout needs the first part's channels to fill whole blocks), else into nhwc and reorders.
  memory up_conv(const UnetLayer& l, const memory& low, const memory& skip, int w, int h) {
    const int ch = static_cast<int>(low.get_desc().dims()[1]);
    const dnnl::resampling_forward::desc rd(dnnl::prop_kind::forward_inference, dnnl::algorithm::resampling_nearest,
                                            low.get_desc(), any({1, ch, h, w}));
    const dnnl::resampling_forward::primitive_desc rpd(rd, engine_);
    memory up(rpd.dst_desc(), engine_);
    steps_.push_back({dnnl::resampling_forward(rpd), {{DNNL_ARG_SRC, low}, {DNNL_ARG_DST, up}}});
    const Conv c = make_conv(l, w, h, true);
    const std::vector<memory::desc> srcs{up.get_desc(), skip.get_desc()};
    dnnl::concat::primitive_desc cpd;
    try {
      cpd = dnnl::concat::primitive_desc(c.pd.src_desc(), 1, srcs, engine_);
    } catch (const dnnl::error&) {
      cpd = dnnl::concat::primitive_desc({{1, l.in, h, w}, memory::data_type::f32, tag::nhwc}, 1, srcs, engine_);
    }
    memory cat(cpd.dst_desc(), engine_);
    steps_.push_back(
        {dnnl::concat(cpd), {{DNNL_ARG_MULTIPLE_SRC, up}, {DNNL_ARG_MULTIPLE_SRC + 1, skip}, {DNNL_ARG_DST, cat}}});
    return add_conv(c, cat);
  }

  dnnl::engine engine_{dnnl::engine::kind::cpu, 0};
  dnnl::stream stream_{engine_};
  std::vector<Step> steps_;
  memory input_, output_;
};

}  // namespace

// ---- weights ----

UnetWeights unet_layers(const UnetWidths& w) {
  const int in[UnetWeights::kLayers] = {kInputs, w.c0, w.c0, w.c1, w.c2, w.c3 + w.c2, w.d2 + w.c1, w.d1 + w.c0, w.d0};
  const int out[UnetWeights::kLayers] = {w.c0, w.c0, w.c1, w.c2, w.c3, w.d2, w.d1, w.d0, kOutputs};
  UnetWeights wts;
  for (size_t i = 0; i < UnetWeights::kLayers; ++i) {
    UnetLayer& l = wts.layers[i];
    l.in = in[i];
    l.out = out[i];
    l.weights.assign(static_cast<size_t>(l.out) * static_cast<size_t>(l.in) * 9, 0.0f);
    l.bias.assign(static_cast<size_t>(l.out), 0.0f);
  }
  return wts;
}

void validate_unet_weights(const UnetWeights& wts) {
  const auto& L = wts.layers;
  for (int i = 0; i < UnetWeights::kLayers; ++i) {
    const UnetLayer& l = L[static_cast<size_t>(i)];
    if (l.out < 1 || l.out > kMaxChannels || l.in < 1 || l.in > kMaxChannels)
      fail(fmt::format("layer L{}: {} → {} channels (1 to {} expected)", i, l.in, l.out, kMaxChannels));
    if (l.weights.size() != static_cast<size_t>(l.out) * l.in * 9 || l.bias.size() != static_cast<size_t>(l.out))
      fail(fmt::format("layer L{}: {} weights and {} biases for {} → {} channels", i, l.weights.size(), l.bias.size(),
                       l.in, l.out));
  }
  const int c0 = L[0].out;
  const UnetWeights shape = unet_layers({c0, L[2].out, L[3].out, L[4].out, L[5].out, L[6].out, L[7].out});
  const char* what[UnetWeights::kLayers] = {"colour, albedo and normal",
                                            "L0's outputs",
                                            "L1's outputs, max-pooled",
                                            "L2's outputs, max-pooled",
                                            "L3's outputs, max-pooled",
                                            "L4's outputs upsampled and L3's concatenated",
                                            "L5's outputs upsampled and L2's concatenated",
                                            "L6's outputs upsampled and L1's concatenated",
                                            "L7's outputs"};
  for (int i = 0; i < UnetWeights::kLayers; ++i)
    if (L[static_cast<size_t>(i)].in != shape.layers[static_cast<size_t>(i)].in)
      fail(fmt::format("layer L{} takes {} input channels, {} expected ({})", i, L[static_cast<size_t>(i)].in,
                       shape.layers[static_cast<size_t>(i)].in, what[i]));
  if (L[1].out != c0) fail(fmt::format("layer L1 gives {} channels, {} expected (L0's width)", L[1].out, c0));
  if (L[8].out != kOutputs) fail(fmt::format("layer L8 gives {} channels, {} expected (RGB)", L[8].out, kOutputs));
}

UnetWeights parse_unet_weights(const unsigned char* data, size_t size) {
  if (!data && size > 0) fail("no data");
  size_t pos = 0;
  const auto need = [&](size_t n, const std::string& what) {
    if (size - pos < n)
      fail(fmt::format("truncated: {} need {} bytes at offset {}, {} left", what, n, pos, size - pos));
  };
  const auto u32 = [&](const std::string& what) {
    need(4, what);
    const uint32_t v = uint32_t(data[pos]) | uint32_t(data[pos + 1]) << 8 | uint32_t(data[pos + 2]) << 16 |
                       uint32_t(data[pos + 3]) << 24;
    pos += 4;
    return v;
  };
  need(8, "the magic");
  if (std::memcmp(data, "KZUNET01", 8) != 0) fail("not a kzw file (the magic \"KZUNET01\" expected)");
  pos = 8;
  const uint32_t count = u32("the layer count");
  if (count != UnetWeights::kLayers) fail(fmt::format("{} layers, {} expected", count, UnetWeights::kLayers));
  UnetWeights wts;
  for (int i = 0; i < UnetWeights::kLayers; ++i) {
    const std::string layer = fmt::format("layer L{}", i);
    const uint32_t out = u32(layer + "'s header"), in = u32(layer + "'s header"), k = u32(layer + "'s header");
    if (out < 1 || out > kMaxChannels)
      fail(fmt::format("{}: {} output channels (1 to {} expected)", layer, out, kMaxChannels));
    if (in < 1 || in > kMaxChannels)
      fail(fmt::format("{}: {} input channels (1 to {} expected)", layer, in, kMaxChannels));
    if (k != 3) fail(fmt::format("{}: kernel size {}, 3 expected", layer, k));
    const size_t nw = size_t(out) * in * 9;
    need((nw + out) * sizeof(float), layer + "'s weights and biases");  // checked before allocating
    UnetLayer& l = wts.layers[static_cast<size_t>(i)];
    l.out = static_cast<int>(out);
    l.in = static_cast<int>(in);
    const auto read = [&](std::vector<float>& v, size_t n, const char* name) {
      v.resize(n);
      for (size_t j = 0; j < n; ++j) {
        v[j] = std::bit_cast<float>(u32(layer));
        if (!std::isfinite(v[j])) fail(fmt::format("{}: {} {} is not finite ({})", layer, name, j, v[j]));
      }
    };
    read(l.weights, nw, "weight");
    read(l.bias, out, "bias");
  }
  need(4, "the end marker");
  if (std::memcmp(data + pos, "END!", 4) != 0) fail(fmt::format("the end marker \"END!\" expected at offset {}", pos));
  pos += 4;
  if (pos != size) fail(fmt::format("{} trailing bytes after the end marker", size - pos));
  validate_unet_weights(wts);
  return wts;
}

const UnetWeights& builtin_unet_weights() {
  if (kUnetWeightsBlobSize == 0)
    throw std::runtime_error("the learned denoiser's weights were not built in (data/denoiser/unet-v1.kzw)");
  static const UnetWeights weights = parse_unet_weights(kUnetWeightsBlob, kUnetWeightsBlobSize);
  return weights;
}

// ---- colour transform ----

UnetTransform UnetTransform::of_image(const float* rgb, size_t pixels) {
  double sum = 0.0;
  add_log_luminance(rgb, pixels, sum);
  return of_sum(sum, pixels);
}

void UnetTransform::add_log_luminance(const float* rgb, size_t pixels, double& sum) {
  for (size_t i = 0; i < pixels; ++i) {
    const double lum =
        0.2126 * sanitize(rgb[3 * i]) + 0.7152 * sanitize(rgb[3 * i + 1]) + 0.0722 * sanitize(rgb[3 * i + 2]);
    sum += std::log(lum + 1e-4);
  }
}

UnetTransform UnetTransform::of_sum(double sum, size_t pixels) {
  if (pixels == 0) return {};
  const double scale = 0.18 / std::exp(sum / static_cast<double>(pixels));
  return {static_cast<float>(std::clamp(scale, 1e-4, 1e4))};
}

float UnetTransform::sanitize(float c) { return std::isfinite(c) && c > 0.0f ? c : 0.0f; }

float UnetTransform::encode(float c) const { return std::log1p(scale * sanitize(c)); }

float UnetTransform::decode(float y) const {
  const float c = std::expm1(std::max(y, 0.0f)) / scale;
  return std::isfinite(c) ? c : 0.0f;
}

// ---- inference ----

namespace {

// Fills rows [y0, y1) of the network's inputs, the whole width, row-major from row y0: colour, albedo and normal, RGB.
using InputRows = std::function<void(int y0, int y1, float* color, float* albedo, float* normal)>;

// run_unet over inputs fetched a row of tiles at a time (with the rows their overlap reads): memory for those rows,
// not for the image's three full-size inputs (75 MB at 1920 × 1080).
std::vector<float> run_unet_rows(const UnetWeights& weights, int w, int h, const InputRows& rows,
                                 const UnetTransform& tr, const UnetSettings& settings,
                                 const std::function<bool()>& expired) {
  if (settings.tile <= 0 || settings.tile % kGrid != 0)
    throw std::invalid_argument(
        fmt::format("run_unet: tile {} is not a positive multiple of {}", settings.tile, kGrid));
  validate_unet_weights(weights);
  const size_t n = static_cast<size_t>(w) * static_cast<size_t>(h);
  std::vector<float> out(3 * n, 0.0f);
  if (n == 0) return out;

  // Cores of equal size (at most `tile`, multiples of 8) that cover the image with as little spare as the grid
  // allows: a 480 × 270 image at tile 256 takes 2 × 2 cores of 240 × 136, not of 256 × 256.
  const auto core_size = [&](int extent) {
    const int tiles = (extent + settings.tile - 1) / settings.tile;
    return round_up((extent + tiles - 1) / tiles, kGrid);
  };
  const int cw = core_size(w), ch = core_size(h);
  const int tw = cw + 2 * kOverlap, th = ch + 2 * kOverlap;
  const size_t plane = static_cast<size_t>(tw) * th;

  const OmpThreads threads(settings.threads);
  std::optional<Network> net;  // built at the first tile that runs, so an expired deadline costs nothing
  bool stopped = false;
  std::vector<float> color, albedo, normal;
  for (int y0 = 0; y0 < h; y0 += ch) {
    const int y1 = std::min(h, y0 + ch);
    // The rows this row of tiles reads: its own and the overlap's, clamped to the image.
    const int r0 = std::max(0, y0 - kOverlap), r1 = std::min(h, y0 - kOverlap + th);
    const size_t band = 3 * static_cast<size_t>(w) * (r1 - r0);
    color.resize(band);
    albedo.resize(band);
    normal.resize(band);
    rows(r0, r1, color.data(), albedo.data(), normal.data());
    for (int x0 = 0; x0 < w; x0 += cw) {
      const int x1 = std::min(w, x0 + cw);
      if (!stopped && expired && expired()) stopped = true;
      if (stopped) {
        for (int y = y0; y < y1; ++y)
          for (int x = x0; x < x1; ++x)
            for (int c = 0; c < 3; ++c)
              out[3 * (static_cast<size_t>(y) * w + x) + c] =
                  UnetTransform::sanitize(color[3 * (static_cast<size_t>(y - r0) * w + x) + c]);
        continue;
      }
      try {
        if (!net) net.emplace(weights, tw, th);
        float* in = net->input();
        for (int ty = 0; ty < th; ++ty) {
          const int sy = std::clamp(y0 - kOverlap + ty, 0, h - 1);
          for (int tx = 0; tx < tw; ++tx) {
            const int sx = std::clamp(x0 - kOverlap + tx, 0, w - 1);
            const size_t i = 3 * (static_cast<size_t>(sy - r0) * w + sx), t = static_cast<size_t>(ty) * tw + tx;
            for (int c = 0; c < 3; ++c) {
              const float a = albedo[i + c], nc = normal[i + c];
              in[c * plane + t] = tr.encode(color[i + c]);
              in[(3 + c) * plane + t] = std::isfinite(a) ? std::clamp(a, 0.0f, 1.0f) : 0.0f;
              in[(6 + c) * plane + t] = std::isfinite(nc) ? nc : 0.0f;
            }
          }
        }
        net->run();
      } catch (const dnnl::error& e) {
        throw std::runtime_error(
            fmt::format("learned denoiser: oneDNN failed: {} (status {})", e.what(), static_cast<int>(e.status)));
      }
      const float* res = net->output();
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
          const size_t t = static_cast<size_t>(y - y0 + kOverlap) * tw + (x - x0 + kOverlap);
          for (int c = 0; c < 3; ++c) out[3 * (static_cast<size_t>(y) * w + x) + c] = tr.decode(res[c * plane + t]);
        }
    }
  }
  return out;
}

}  // namespace

std::vector<float> run_unet(const UnetWeights& weights, int w, int h, const std::vector<float>& color,
                            const std::vector<float>& albedo, const std::vector<float>& normal,
                            const UnetSettings& settings, const std::function<bool()>& expired) {
  if (w < 0 || h < 0) throw std::invalid_argument(fmt::format("run_unet: image size {} x {}", w, h));
  const size_t n = static_cast<size_t>(w) * static_cast<size_t>(h);
  if (color.size() != 3 * n || albedo.size() != 3 * n || normal.size() != 3 * n)
    throw std::invalid_argument(
        fmt::format("run_unet: {} x {} pixels need {} values a buffer; colour {}, albedo {}, normal {}", w, h, 3 * n,
                    color.size(), albedo.size(), normal.size()));
  const auto copy_rows = [&](int y0, int y1, float* c, float* a, float* nm) {
    const size_t from = 3 * static_cast<size_t>(y0) * w, count = 3 * static_cast<size_t>(y1 - y0) * w;
    std::copy_n(color.begin() + static_cast<ptrdiff_t>(from), count, c);
    std::copy_n(albedo.begin() + static_cast<ptrdiff_t>(from), count, a);
    std::copy_n(normal.begin() + static_cast<ptrdiff_t>(from), count, nm);
  };
  return run_unet_rows(weights, w, h, copy_rows, UnetTransform::of_image(color.data(), n), settings, expired);
}

std::vector<float> denoise_learned(const Film& film, const VisibleEmission* emission,
                                   const std::function<bool()>& expired, const UnetSettings& settings) {
  return denoise_learned(builtin_unet_weights(), film, emission, expired, settings);
}

std::vector<float> denoise_learned(const UnetWeights& weights, const Film& film, const VisibleEmission* emission,
                                   const std::function<bool()>& expired, const UnetSettings& settings) {
  using namespace denoise_detail;
  VisibleEmission own;
  const VisibleEmission& visible = emission_to_add_back(film, emission, own, "denoise_learned");
  const int w = film.width(), h = film.height();
  const size_t n = film.pixels().size();
  if (n == 0) return {};
  // The network's inputs made from bands of the half buffers (pixels without samples in a half filled from their
  // neighbours), a row of tiles at a time: full-image inputs were 75 MB at 1920 × 1080. The exposure, of the whole
  // image, takes a pass of its own (the same sum, in the same order, as of_image's over the full colour).
  const HalfBufferRows half_buffers(film, visible);
  constexpr int kRows = 64;
  const auto fill = [&](int y0, int y1, float* color, float* albedo, float* normal) {
    for (int b0 = y0; b0 < y1; b0 += kRows) {
      const Buffers b = half_buffers.rows(b0, std::min(y1, b0 + kRows));
      for (int y = b.y0; y < b.y1; ++y)
        for (int x = 0; x < w; ++x) {
          const size_t i = static_cast<size_t>(y - y0) * w + x, j = b.index(x, y);
          const Vec3 c = 0.5f * (b.half[0][j] + b.half[1][j]);
          for (int k = 0; k < 3; ++k) {
            color[3 * i + k] = c[k];
            if (albedo) albedo[3 * i + k] = b.albedo[j][k];
            if (normal) normal[3 * i + k] = b.normal[j][k];
          }
        }
    }
  };
  double log_sum = 0.0;
  std::vector<float> color(3 * static_cast<size_t>(w) * kRows);
  for (int y0 = 0; y0 < h; y0 += kRows) {
    const int y1 = std::min(h, y0 + kRows);
    fill(y0, y1, color.data(), nullptr, nullptr);
    UnetTransform::add_log_luminance(color.data(), static_cast<size_t>(w) * (y1 - y0), log_sum);
  }
  std::vector<float>().swap(color);
  std::vector<float> out = run_unet_rows(weights, w, h, fill, UnetTransform::of_sum(log_sum, n), settings, expired);
  for (size_t i = 0; i < n; ++i) put_pixel(out, i, Vec3(out[3 * i], out[3 * i + 1], out[3 * i + 2]), visible);
  return out;
}

}  // namespace kozu
