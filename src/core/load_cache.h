// Files the scene loader has read, kept for the next load of an edited scene: the Python module's kozu.Scene renders
// its dict again after an edit without reading its unchanged meshes, voxel grids, glTF files and images again.
//
// The readers (io/mesh_io.h load_mesh, media/voxel_grid.h VoxelGrid::load, io/gltf_reader.h read_gltf,
// io/image_io.h read_image) go through cached_load: while a LoadCache::Scope lives, a file's value is reused as
// long as the file keeps its size and modification time, and read (and kept) otherwise; with no scope they read as
// always. A cached value is copied out (the scene then owns and may change its copy); a failed read is not kept.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>

namespace kozu {

class LoadCache {
 public:
  struct Stats {
    uint64_t hits = 0, misses = 0;
    size_t entries = 0;
  };
  Stats stats() const;
  void clear();

  // The cache the readers use while this lives (the one before it again after); one load at a time may use one.
  class Scope {
   public:
    explicit Scope(LoadCache* cache);
    ~Scope();
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;

   private:
    LoadCache* previous_;
  };
  static LoadCache* current();

  // The value load() makes for (kind, file, variant): the kept one while the file is unchanged.
  template <class T, class Load>
  T get(std::string_view kind, const std::filesystem::path& file, std::string_view variant, Load&& load) {
    const Key key = make_key(kind, file, variant);
    if (std::shared_ptr<const void> v = find(key)) return *static_cast<const T*>(v.get());
    auto value = std::make_shared<const T>(load());
    keep(key, value);
    return *value;
  }

 private:
  struct Key {
    std::string name;  // kind, absolute path and variant
    uintmax_t size = 0;
    int64_t mtime = 0;
    bool stat_ok = false;
  };
  struct Entry {
    uintmax_t size = 0;
    int64_t mtime = 0;
    std::shared_ptr<const void> value;
  };
  static Key make_key(std::string_view kind, const std::filesystem::path& file, std::string_view variant);
  std::shared_ptr<const void> find(const Key& key);
  void keep(const Key& key, std::shared_ptr<const void> value);

  mutable std::mutex mutex_;
  std::map<std::string, Entry> entries_;
  Stats stats_;
};

// load() through the current cache (LoadCache::Scope), or directly when there is none.
template <class T, class Load>
T cached_load(std::string_view kind, const std::filesystem::path& file, std::string_view variant, Load&& load) {
  LoadCache* cache = LoadCache::current();
  if (!cache) return load();
  return cache->get<T>(kind, file, variant, std::forward<Load>(load));
}

}  // namespace kozu
