#include "support/render_test.h"

#include "io/image_io.h"

#include <fmt/format.h>
#include <fstream>

#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <random>
#include <stdexcept>
#include <thread>

namespace kozu::test {

TestRender render_json(const std::string& json, int spp, int threads, uint64_t seed,
                       const std::filesystem::path& base_dir) {
  TestRender t;
  t.scene = load_scene_text(json, "scene.json", base_dir);
  const Vec2i res = t.scene->camera.resolution();
  t.film = Film(res.x, res.y);
  PathIntegrator integrator(*t.scene, t.scene->settings.max_depth, t.scene->settings.direct);
  RenderSettings opt;
  opt.spp = spp;
  opt.threads = threads;
  opt.seed = seed;
  opt.filter = t.scene->settings.filter;
  t.result = render(*t.scene, integrator, t.film, opt);
  // Valid scenes give finite samples, and no test scene needs the per-path work cap.
  EXPECT_EQ(t.result.film.discarded_samples, 0u) << "NaN, Inf or negative samples from a valid scene";
  EXPECT_EQ(t.result.rays.truncated_paths, 0u) << "paths cut by the per-path work cap";
  return t;
}

namespace {
// z with P(|N(0,1)| > z) = p, by bisection on erfc.
double normal_quantile_two_sided(double p) {
  double lo = 0.0, hi = 40.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (std::erfc(mid / std::sqrt(2.0)) > p)
      lo = mid;
    else
      hi = mid;
  }
  return 0.5 * (lo + hi);
}
}  // namespace

void expect_matches_reference(const Film& film, const Image& ref, int block) {
  ASSERT_EQ(ref.width, film.width());
  ASSERT_EQ(ref.height, film.height());
  const int kBlock = block, kBlocks = (film.width() / kBlock) * (film.height() / kBlock) * 3;
  const double alpha = 1.0 - std::pow(1.0 - 0.01, 1.0 / kBlocks);
  const double z = normal_quantile_two_sided(alpha);
  int failures = 0;
  double worst = 0;
  for (int by = 0; by + kBlock <= film.height(); by += kBlock)
    for (int bx = 0; bx + kBlock <= film.width(); bx += kBlock)
      for (int c = 0; c < 3; ++c) {
        double sum = 0, ref_sum = 0, var = 0;
        for (int y = by; y < by + kBlock; ++y)
          for (int x = bx; x < bx + kBlock; ++x) {
            sum += film.mean(x, y)[c];
            var += film.variance_of_mean(x, y)[c];
            ref_sum += ref.data[3 * (static_cast<size_t>(y) * film.width() + x) + c];
          }
        const double n = kBlock * kBlock;
        const double diff = std::abs(sum - ref_sum) / n;
        const double se = std::sqrt(var) / n;
        worst = std::max(worst, diff / se);
        if (diff > z * se) {
          ++failures;
          ADD_FAILURE() << fmt::format(
              "block ({}, {}) channel {}: mean {:.5f} vs reference {:.5f}, {:.2f} standard errors (limit {:.2f})", bx,
              by, c, sum / n, ref_sum / n, diff / se, z);
        }
      }
  EXPECT_EQ(failures, 0) << "worst block deviation " << worst << " standard errors";
}

ImageStats image_stats(const Film& film) {
  Vec3d sum(0.0), var_sum(0.0);
  const double n = static_cast<double>(film.width()) * film.height();
  for (int y = 0; y < film.height(); ++y)
    for (int x = 0; x < film.width(); ++x) {
      sum += Vec3d(film.mean(x, y));
      var_sum += Vec3d(film.variance_of_mean(x, y));
    }
  ImageStats s;
  s.mean = Rgb(sum / n);
  s.standard_error = Rgb(glm::sqrt(var_sum) / n);
  return s;
}

// Compiled in by CMake; the environment can override them (e.g. to test an installed binary).
std::filesystem::path source_dir() {
  const char* s = std::getenv("KOZU_SOURCE_DIR");
  return s ? s : KOZU_TEST_SOURCE_DIR;
}

std::filesystem::path kozu_binary() {
  const char* s = std::getenv("KOZU_BINARY");
  return s ? s : KOZU_TEST_BINARY;
}

int run_command(const std::string& command, std::string* output) {
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  if (!p) return -1;
  char buf[4096];
  std::string out;
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
  const int status = pclose(p);
  if (output) *output = out;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

ChildProcess::ChildProcess(const std::string& command, const std::filesystem::path& log)
    : log_(log), start_(std::chrono::steady_clock::now()) {
  pid_ = fork();
  if (pid_ == 0) {
    const std::string line = "exec " + command + " > '" + log.string() + "' 2>&1";
    execl("/bin/sh", "sh", "-c", line.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  EXPECT_GT(pid_, 0) << "fork failed";
}

ChildProcess::~ChildProcess() {
  if (pid_ > 0 && !reaped_) {
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
  }
}

void ChildProcess::signal(int sig) const {
  if (pid_ > 0 && !reaped_) kill(pid_, sig);
}

bool ChildProcess::wait_until_catches(int sig, double seconds) const {
  // The child is `sh -c "exec ..."` until the exec, and dash with -c catches SIGINT itself: its SigCgt must not
  // count (it did: under load kozu got SIGINT before installing its handler and died of it).
  std::error_code ec;
  const auto shell = std::filesystem::canonical("/bin/sh", ec);
  const auto exe = fmt::format("/proc/{}/exe", pid_);
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < until) {
    const auto running = std::filesystem::read_symlink(exe, ec);
    if (ec || running == shell) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
      continue;
    }
    std::ifstream status(fmt::format("/proc/{}/status", pid_));
    std::string line;
    while (std::getline(status, line)) {
      if (line.rfind("SigCgt:", 0) != 0) continue;
      const unsigned long long mask = std::stoull(line.substr(7), nullptr, 16);
      if ((mask >> (sig - 1)) & 1ull) return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

std::optional<int> ChildProcess::wait(double seconds) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  for (;;) {
    int status = 0;
    const pid_t r = waitpid(pid_, &status, WNOHANG);
    if (r == pid_) {
      reaped_ = true;
      return status;
    }
    if (std::chrono::steady_clock::now() >= until) return std::nullopt;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

double ChildProcess::seconds_since_start() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

std::string ChildProcess::log() const {
  std::ifstream in(log_);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TempDir::TempDir() {
  std::random_device rd;
  path_ = std::filesystem::temp_directory_path() / ("kozu-test-" + std::to_string(rd()) + std::to_string(rd()));
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

std::filesystem::path write_test_exr(const std::filesystem::path& file, int width, int height,
                                     const std::function<float(int, int, int)>& f) {
  std::vector<float> px(size_t(width) * size_t(height) * 3);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < 3; ++c) px[(size_t(y) * size_t(width) + size_t(x)) * 3 + size_t(c)] = f(x, y, c);
  write_image(file, width, height, px, ToneMap{});
  return file;
}

std::filesystem::path TempDir::write(const std::string& name, std::string_view contents) const {
  const std::filesystem::path path = path_ / name;
  std::ofstream out(path, std::ios::binary);
  out.write(contents.data(), std::streamsize(contents.size()));
  EXPECT_TRUE(out.good()) << path;
  return path;
}

RelativeCacheRender render_with_relative_cache(const TempDir& dir, const std::string& material) {
  std::filesystem::create_directories(dir.path() / "sub");
  write_test_exr(dir.path() / "sub" / "bumps.exr", 16, 16, [](int x, int, int c) {
    return c == 0 ? (x % 4 < 2 ? 0.3f : 0.7f) : c == 1 ? 0.5f : 0.95f;
  });
  dir.write("sub/scene.json", fmt::format(R"({{"camera": {{"type": "orthographic", "position": [0, 0, 5],
      "look_at": [0, 0, 0], "scale": 1, "resolution": [4, 4]}},
    "materials": {{"m": {}}},
    "shapes": [{{"type": "quad", "material": "m", "vertices": [[-2, -2, 0], [2, -2, 0], [2, 2, 0], [-2, 2, 0]]}}],
    "lights": [{{"type": "environment", "radiance": 1}}]}})",
                                          material));
  RelativeCacheRender r;
  r.status = run_command(fmt::format("cd '{}' && '{}' render sub/scene.json -o sub/out.exr --spp 1 --quiet 2>&1",
                                     dir.path().string(), kozu_binary().string()),
                         &r.output);
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir.path() / "sub" / ".kozu-tx", ec))
    r.cached.push_back(e.path().filename().string());
  return r;
}

}  // namespace kozu::test
