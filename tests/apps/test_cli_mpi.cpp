// `mpirun -np N kozu render`: the ranks split the tiles and rank 0 writes the sum of their films, which is the
// single-process image bit for bit (apps/mpi_world.h), also when resuming a checkpoint, and under the default
// "direct": "ltc", whose pixels learn from their neighbours' (each rank traces again the pilot samples of the pixels
// around its tiles: PixelMemory); run as processes with 2 and 4 ranks on this machine (--oversubscribe: more ranks
// than cores is fine for a test).
#include "apps/cli_helpers.h"

#include "io/image_io.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

namespace kozu::test {
namespace {

const char* kScene = R"({
  "camera": {"position": [0, 1, 4], "look_at": [0, 0.5, 0], "fov": 40, "resolution": [80, 60]},
  "render": {"spp": 8, "max_depth": 4},
  "materials": {"floor": {"type": "diffuse", "albedo": 0.6},
                "ball": {"type": "conductor", "eta": [0.2, 0.45, 1.3], "k": [3.6, 2.6, 2.0], "roughness": 0.3}},
  "shapes": [{"type": "quad", "material": "floor", "vertices": [[-3, 0, 3], [3, 0, 3], [3, 0, -3], [-3, 0, -3]]},
             {"type": "sphere", "center": [0, 0.6, 0], "radius": 0.6, "material": "ball"},
             {"type": "quad", "material": "floor", "emission": [6, 5, 4],
              "vertices": [[-0.5, 2.5, -0.5], [0.5, 2.5, -0.5], [0.5, 2.5, 0.5], [-0.5, 2.5, 0.5]]}],
  "lights": [{"type": "environment", "radiance": 0.8}, {"type": "point", "position": [1, 3, 1], "intensity": 8}] })";

std::string mpirun(int ranks) {
  return fmt::format("'{}' --allow-run-as-root --oversubscribe -np {} {}", KOZU_TEST_MPIEXEC, ranks, kozu());
}

bool same_pixels(const Image& a, const Image& b) {
  return a.width == b.width && a.height == b.height && a.data == b.data;
}

// Every rank makes the same choice of pixels whose visible emission is supersampled apart
// (render/emission_supersampling.h) over the whole window, so the reduced film is the single process's.
TEST(Mpi, RanksSupersampleTheVisibleEmissionAsOneProcess) {
  TempDir dir;
  const auto scene = dir.write("s.json", R"({
    "camera": {"position": [0, 1, 4], "look_at": [0, 0.5, 0], "fov": 40, "resolution": [80, 60]},
    "render": {"spp": 16, "max_depth": 4},
    "materials": {"floor": {"type": "diffuse", "albedo": 0.6}},
    "shapes": [{"type": "quad", "material": "floor", "vertices": [[-3, 0, 3], [3, 0, 3], [3, 0, -3], [-3, 0, -3]]},
               {"type": "sphere", "center": [0.2, 0.6, 0], "radius": 0.3, "emission": [20, 18, 15]}] })")
                          .string();
  const auto d = dir.path().string();
  std::string log;
  ASSERT_EQ(
      run_command(fmt::format("{} render '{}' -q -o '{}/one.exr' --stats '{}/one.json'", kozu(), scene, d, d), &log), 0)
      << log;
  const uint64_t pixels = read_json(dir.path() / "one.json")["emission_supersampling"]["pixels"].get<uint64_t>();
  EXPECT_GT(pixels, 0u) << "the sphere's edge";
  ASSERT_EQ(run_command(fmt::format("{} render '{}' -q -o '{}/two.exr' --stats '{}/two.json'", mpirun(2), scene, d, d),
                        &log),
            0)
      << log;
  EXPECT_TRUE(same_pixels(read_image(dir.path() / "two.exr"), read_image(dir.path() / "one.exr")));
  EXPECT_EQ(read_json(dir.path() / "two.json")["emission_supersampling"]["pixels"].get<uint64_t>(), pixels);
}

TEST(Mpi, RanksGiveTheSingleProcessImageBitForBit) {
  TempDir dir;
  const auto scene = dir.write("s.json", kScene).string();
  const auto d = dir.path().string();
  std::string log;
  ASSERT_EQ(
      run_command(fmt::format("{} render '{}' -q -o '{}/one.exr' --stats '{}/one.json'", kozu(), scene, d, d), &log), 0)
      << log;
  const Image one = read_image(dir.path() / "one.exr");
  const nlohmann::json one_stats = read_json(dir.path() / "one.json");
  EXPECT_GT(one_stats["ltc"]["pixels_taking"].get<uint64_t>(), 0u) << "the quad light's control variate";
  for (const int n : {2, 4}) {
    const auto out = fmt::format("{}/np{}.exr", d, n), stats = fmt::format("{}/np{}.json", d, n);
    ASSERT_EQ(run_command(fmt::format("{} render '{}' -q -o '{}' --stats '{}'", mpirun(n), scene, out, stats), &log), 0)
        << log;
    EXPECT_TRUE(same_pixels(read_image(out), one)) << n << " ranks";
    const nlohmann::json j = read_json(stats);
    EXPECT_EQ(j["mpi_ranks"].get<int>(), n);
    EXPECT_EQ(j["paths"].get<uint64_t>(), one_stats["paths"].get<uint64_t>()) << n << " ranks";
    EXPECT_EQ(j["spp_min"].get<int>(), 8);
  }
  // A single-process checkpoint at 3 spp, resumed by 2 ranks to 8.
  ASSERT_EQ(
      run_command(fmt::format("{} render '{}' --spp 3 -q -o '{}/c.exr' --checkpoint '{}/c.kzc'", kozu(), scene, d, d),
                  &log),
      0)
      << log;
  ASSERT_EQ(
      run_command(fmt::format("{} render '{}' --spp 8 -q -o '{}/r.exr' --resume '{}/c.kzc'", mpirun(2), scene, d, d),
                  &log),
      0)
      << log;
  EXPECT_TRUE(same_pixels(read_image(dir.path() / "r.exr"), one));
  // Periodic partial images need the whole film on one rank: refused with a message.
  EXPECT_EQ(
      run_command(fmt::format("{} render '{}' -q -o '{}/p.exr' --partial-every 1", mpirun(2), scene, d), &log) != 0,
      true);
  EXPECT_NE(log.find("not supported across MPI ranks"), std::string::npos) << log;
}

// A failure on one rank ends every rank with a message naming it, instead of a deadlock (the failed rank waited
// in MPI_Finalize while the others waited in the film's reduction), and ranks started with different settings are
// refused before rendering instead of aborting with MPI_ERR_TRUNCATE or writing an image with holes. mpirun's
// multiple-program form (A : B) starts ranks with different command lines.
TEST(Mpi, OneRanksFailureOrOtherSettingsStopEveryRank) {
  TempDir dir;
  const auto scene = dir.write("s.json", kScene).string();
  const auto bad = dir.write("bad.json", R"({"camera": {"fov": "wide"}})").string();
  const auto d = dir.path().string();
  const std::string mpiexec = fmt::format("'{}' --allow-run-as-root --oversubscribe", KOZU_TEST_MPIEXEC);
  struct Case {
    std::string rank1, message;
  };
  const Case cases[] = {
      {fmt::format("render '{}' -q -o '{}/b.exr'", bad, d), "rank 1 failed before rendering"},
      {fmt::format("render '{}' -q -o '/proc/no/b.exr'", scene), "rank 1 failed before rendering"},
      {fmt::format("render '{}' -q -o '{}/b.exr' --spp 4", scene, d), "rank 1 was started with other settings"},
      {fmt::format("render '{}' -q -o '{}/b.exr' --seed 9", scene, d), "rank 1 was started with other settings"},
      {fmt::format("render '{}' -q -o '{}/b.exr' --bogus", scene, d), "rank 1 failed before rendering"},
  };
  for (const Case& c : cases) {
    ChildProcess run(fmt::format("{} -np 1 {} render '{}' -q -o '{}/a.exr' : -np 1 {} {}", mpiexec, kozu(), scene, d,
                                 kozu(), c.rank1),
                     dir.path() / "log.txt");
    const std::optional<int> status = run.wait(60.0);
    ASSERT_TRUE(status) << c.rank1 << ": the job hung\n" << run.log();
    EXPECT_NE(*status, 0) << c.rank1;
    EXPECT_NE(run.log().find(c.message), std::string::npos) << c.rank1 << "\n" << run.log();
    EXPECT_FALSE(std::filesystem::exists(dir.path() / "a.exr")) << c.rank1;
  }
}

}  // namespace
}  // namespace kozu::test
