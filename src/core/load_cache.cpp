#include "core/load_cache.h"

#include <atomic>

namespace kozu {

namespace {
std::atomic<LoadCache*> g_current{nullptr};
}  // namespace

LoadCache::Scope::Scope(LoadCache* cache) : previous_(g_current.exchange(cache)) {}
LoadCache::Scope::~Scope() { g_current.store(previous_); }
LoadCache* LoadCache::current() { return g_current.load(); }

LoadCache::Stats LoadCache::stats() const {
  std::lock_guard lock(mutex_);
  Stats s = stats_;
  s.entries = entries_.size();
  return s;
}

void LoadCache::clear() {
  std::lock_guard lock(mutex_);
  entries_.clear();
}

LoadCache::Key LoadCache::make_key(std::string_view kind, const std::filesystem::path& file, std::string_view variant) {
  Key k;
  std::error_code ec;
  std::filesystem::path abs = std::filesystem::absolute(file, ec);
  if (ec) abs = file;
  k.name.append(kind).push_back('\0');
  k.name.append(abs.lexically_normal().string()).push_back('\0');
  k.name.append(variant);
  k.size = std::filesystem::file_size(file, ec);
  const bool size_ok = !ec;
  const auto t = std::filesystem::last_write_time(file, ec);
  k.mtime = ec ? 0 : static_cast<int64_t>(t.time_since_epoch().count());
  k.stat_ok = size_ok && !ec;
  return k;
}

std::shared_ptr<const void> LoadCache::find(const Key& key) {
  std::lock_guard lock(mutex_);
  const auto it = entries_.find(key.name);
  // A file that cannot be examined is read again (its reader reports what is wrong with it).
  if (key.stat_ok && it != entries_.end() && it->second.size == key.size && it->second.mtime == key.mtime) {
    ++stats_.hits;
    return it->second.value;
  }
  ++stats_.misses;
  return nullptr;
}

void LoadCache::keep(const Key& key, std::shared_ptr<const void> value) {
  if (!key.stat_ok) return;
  std::lock_guard lock(mutex_);
  entries_[key.name] = Entry{key.size, key.mtime, std::move(value)};
}

}  // namespace kozu
