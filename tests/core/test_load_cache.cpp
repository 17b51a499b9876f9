// The cache of files scene loads read (core/load_cache.h): a file is read once while it is unchanged, again when
// its size or modification time changes, never kept when its read fails, and not at all without a scope.
#include "core/load_cache.h"
#include "io/mesh_io.h"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace kozu {
namespace {

std::filesystem::path scratch_file(const std::string& name, const std::string& text) {
  const auto dir = std::filesystem::temp_directory_path() / "kozu-test-load-cache";
  std::filesystem::create_directories(dir);
  const auto p = dir / name;
  std::ofstream(p) << text;
  return p;
}

int counted_read(int& reads) { return ++reads; }

TEST(LoadCache, ReadsAFileOnceWhileItIsUnchanged) {
  const auto file = scratch_file("a.txt", "one");
  LoadCache cache;
  LoadCache::Scope scope(&cache);
  int reads = 0;
  EXPECT_EQ(cached_load<int>("test", file, "", [&] { return counted_read(reads); }), 1);
  EXPECT_EQ(cached_load<int>("test", file, "", [&] { return counted_read(reads); }), 1);
  EXPECT_EQ(reads, 1);
  // Another variant (other read options) or kind is another value.
  EXPECT_EQ(cached_load<int>("test", file, "v2", [&] { return counted_read(reads); }), 2);
  EXPECT_EQ(cached_load<int>("other", file, "", [&] { return counted_read(reads); }), 3);
  const LoadCache::Stats s = cache.stats();
  EXPECT_EQ(s.hits, 1u);
  EXPECT_EQ(s.misses, 3u);
  EXPECT_EQ(s.entries, 3u);
}

TEST(LoadCache, ReadsAChangedFileAgain) {
  const auto file = scratch_file("b.txt", "one");
  LoadCache cache;
  LoadCache::Scope scope(&cache);
  int reads = 0;
  cached_load<int>("test", file, "", [&] { return counted_read(reads); });
  std::filesystem::last_write_time(file, std::filesystem::last_write_time(file) + std::chrono::seconds(2));
  EXPECT_EQ(cached_load<int>("test", file, "", [&] { return counted_read(reads); }), 2);
  std::ofstream(file) << "a longer text";  // and its size
  EXPECT_EQ(cached_load<int>("test", file, "", [&] { return counted_read(reads); }), 3);
  EXPECT_EQ(cached_load<int>("test", file, "", [&] { return counted_read(reads); }), 3);
}

TEST(LoadCache, KeepsNoFailedRead) {
  const auto file = scratch_file("c.txt", "one");
  LoadCache cache;
  LoadCache::Scope scope(&cache);
  EXPECT_THROW(cached_load<int>("test", file, "", []() -> int { throw std::runtime_error("bad"); }),
               std::runtime_error);
  int reads = 0;
  EXPECT_EQ(cached_load<int>("test", file, "", [&] { return counted_read(reads); }), 1);
  EXPECT_EQ(cache.stats().entries, 1u);
}

TEST(LoadCache, NothingIsKeptOutsideAScope) {
  const auto file = scratch_file("d.txt", "one");
  LoadCache cache;
  {
    LoadCache::Scope scope(&cache);
    EXPECT_EQ(LoadCache::current(), &cache);
  }
  EXPECT_EQ(LoadCache::current(), nullptr);
  int reads = 0;
  cached_load<int>("test", file, "", [&] { return counted_read(reads); });
  cached_load<int>("test", file, "", [&] { return counted_read(reads); });
  EXPECT_EQ(reads, 2);
  EXPECT_EQ(cache.stats().misses, 0u);
}

// The mesh reader goes through the cache: the second read of a mesh file is the first one's copy.
TEST(LoadCache, MeshReaderUsesIt) {
  const auto file = scratch_file("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  LoadCache cache;
  LoadCache::Scope scope(&cache);
  const MeshData a = load_mesh(file);
  const MeshData b = load_mesh(file);
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.indices, b.indices);
  EXPECT_EQ(cache.stats().hits, 1u);
  EXPECT_EQ(cache.stats().misses, 1u);
}

}  // namespace
}  // namespace kozu
