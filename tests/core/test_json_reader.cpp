// The JSON reader against what a user or a file can give it: flags of the tool commands read by the scene keys'
// rules, array elements past the end, and a scene too large for the memory left.
#include "core/json_reader.h"

#include "support/sanitizer.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <cstdio>
#include <fstream>
#include <functional>
#include <string>

namespace kozu::test {
namespace {

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

// The tool commands' flags (fit-ltc, voxelize, procedural, precompute, sss-reference) went through CLI11's
// validators, whose failures are usage errors (exit 2); they are read by the rules of scene keys, as InputErrors
// naming the command and the flag.
TEST(JsonReader, ToolFlagValues) {
  EXPECT_EQ(integer_flag_value("010", "kozu x", "--n", Range::closed(0, 100)), 10);
  EXPECT_EQ(message_of([] { integer_flag_value("1", "kozu fit-ltc", "--size", Range::closed(2, 256)); }),
            "kozu fit-ltc: --size: expected an integer in [2, 256], got 1");
  EXPECT_EQ(message_of([] { integer_flag_value("0x10", "kozu x", "--n", Range::closed(0, 100)); }),
            "kozu x: --n: expected an integer in [0, 100], got the string \"0x10\"");
  EXPECT_EQ(message_of([] { integer_flag_value("", "kozu x", "--n", Range::closed(0, 100)); }),
            "kozu x: --n: expected an integer in [0, 100], got the string \"\"");
  EXPECT_DOUBLE_EQ(number_flag_value("1e6", "kozu x", "--photons"), 1e6);
  EXPECT_EQ(message_of([] { number_flag_value("nan", "kozu x", "--mfp", Range::positive()); }),
            "kozu x: --mfp: expected a number > 0, got the string \"nan\"");
  EXPECT_EQ(message_of([] { number_flag_value("1e999", "kozu x", "--mfp"); }),
            "kozu x: --mfp: expected a finite number, got inf");
  EXPECT_EQ(uint64_flag_value("18446744073709551615", "kozu x", "--seed"), 18446744073709551615u);
  EXPECT_EQ(message_of([] { uint64_flag_value("-1", "kozu x", "--seed"); }),
            "kozu x: --seed: expected an integer in [0, 18446744073709551615], got -1");
  EXPECT_EQ(choice_flag_value("yarn", "kozu procedural", "the volume", {"smoke", "yarn"}), "yarn");
  EXPECT_EQ(message_of([] {
              choice_flag_value("smok", "kozu procedural", "the volume", {"smoke", "yarn"});
            }),
            "kozu procedural: the volume: expected one of smoke, yarn, got 'smok' (did you mean 'smoke'?)");
}

// An element past an array's end was read with nlohmann's unchecked operator[] (undefined behaviour; at() would
// have put "[json.exception.out_of_range.401] ..." before the user): a message with the array's path.
TEST(JsonReader, ArrayElementsPastTheEndAreAMessage) {
  auto source = std::make_shared<JsonSource>(JsonSource{"s.json", "."});
  const Json j = Json::parse(R"({"a": [1, 2]})");
  const JsonArray a = JsonObject(j, "", source).get_array("a");
  EXPECT_EQ(a.number(1), 2.0f);
  EXPECT_EQ(message_of([&] { a.number(2); }), "s.json: /a: expected an array of at least 3 elements, got 2");
  EXPECT_EQ(message_of([&] { a.integer(5, Range::closed(0, 9)); }),
            "s.json: /a: expected an array of at least 6 elements, got 2");
  EXPECT_EQ(message_of([&] { a.vec3(2); }), "s.json: /a: expected an array of at least 3 elements, got 2");
  EXPECT_EQ(message_of([&] { a.object(3); }), "s.json: /a: expected an array of at least 4 elements, got 2");
}

// The address space this process uses now, in bytes (VmSize), or 0.
size_t address_space_bytes() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmSize:", 0) == 0) return std::stoull(line.substr(7)) * 1024;
  return 0;
}

// In a death test's child: parses text with the address space limited to what is used now plus 64 MiB; exits 0
// when the parse ends in the out-of-memory message (printed), else with a code saying what went wrong.
[[noreturn]] void parse_under_a_limit(const std::string& text) {
  const size_t used = address_space_bytes();
  if (used == 0) std::_Exit(4);
  const rlimit limit{used + (size_t{64} << 20), used + (size_t{64} << 20)};
  if (setrlimit(RLIMIT_AS, &limit) != 0) std::_Exit(5);
  try {
    parse_json_text(text, "big.json");
    std::_Exit(2);  // it fit: the test is wrong
  } catch (const InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    std::_Exit(std::string(e.what()).rfind("big.json: out of memory while reading the scene (", 0) == 0 ? 0 : 3);
  }
}

// A large scene parsed under an address-space limit (ulimit -v) ended in "terminate called after throwing an
// instance of 'std::bad_alloc'": the partial document was destroyed while the error unwound, and nlohmann's
// destructor allocates. It is one message naming the file. Run in a child process (a death test) whose limit is
// what it uses already plus 64 MiB, far less than the document needs (several times the text's 24 MB).
TEST(JsonReader, SceneTooLargeForTheMemoryLeftIsOneMessage) {
  if (kSanitized) GTEST_SKIP() << "AddressSanitizer's shadow memory rules out an address-space limit";
  std::string text = R"({"shapes": [{"type": "mesh", "positions": [)";
  for (int i = 0; i < 1200000; ++i) text += fmt::format("{}[{}, 0.25, 0.5]", i ? "," : "", i);
  text += "]}]}";
  ASSERT_GT(text.size(), 20u << 20);
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(parse_under_a_limit(text), testing::ExitedWithCode(0),
              "big.json: out of memory while reading the scene \\([0-9.]+ MB\\)");
  // Without the limit the same text parses.
  EXPECT_EQ(parse_json_text(text, "big.json")["shapes"][0]["positions"].size(), 1200000u);
}

}  // namespace
}  // namespace kozu::test
