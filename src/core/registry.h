// The one mechanism that turns a JSON description into a model, for every kind the scene format names
// (materials/registry.cpp, media/registry.cpp, lights/registry.cpp, geometry/shape_registry.cpp,
// textures/texture_parse.cpp).
//
// Each kind has a table of entries {"type", parse}. Scene loading has three phases (scene/scene_loader.h), and
// the table serves the first: `parse` reads and validates every key of the description (all errors found before
// any heavy I/O) and returns a Deferred: the model itself when it needs no file, or the job that reads its files
// and builds it, which the loader runs in the load phase, for all models at once in parallel.
#pragma once

#include "core/json_reader.h"

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace kozu {

template <class T>
class Deferred {
 public:
  Deferred() = default;
  // Ready now (any unique_ptr to a T or a class derived from it).
  template <class U>
  Deferred(std::unique_ptr<U> ready) : ready_(std::move(ready)) {}  // NOLINT: implicit on purpose
  // Built by a job that reads files; the job throws InputError with the JSON path of what failed.
  explicit Deferred(std::function<std::unique_ptr<T>()> load) : load_(std::move(load)) {}

  bool needs_load() const { return static_cast<bool>(load_); }
  // Runs the load job (once). Different Deferred objects may load concurrently.
  void load() {
    if (!load_) return;
    ready_ = load_();
    load_ = nullptr;
  }
  std::unique_ptr<T> take() {
    load();
    return std::move(ready_);
  }

 private:
  std::unique_ptr<T> ready_;
  std::function<std::unique_ptr<T>()> load_;
};

// One row of a kind's table. Args: what every parser of the kind needs besides its JSON (none for most kinds).
template <class T, class... Args>
struct RegistryEntry {
  const char* type;
  Deferred<T> (*parse)(const JsonObject& desc, Args... args);
};

// Parses desc with the entry named by its "type" key (default_type when it has none), then reports keys that
// no one read (JsonObject::finish). The type is stored in *type when asked for.
template <class T, size_t N, class... Args>
Deferred<T> parse_by_type(const JsonObject& desc, const RegistryEntry<T, Args...> (&table)[N],
                          std::optional<std::string> default_type = {}, std::string* type = nullptr,
                          std::type_identity_t<Args>... args) {
  std::vector<std::string> types;
  for (const RegistryEntry<T, Args...>& e : table) types.emplace_back(e.type);
  const std::string name = desc.get_enum("type", types, std::move(default_type));
  if (type) *type = name;
  for (const RegistryEntry<T, Args...>& e : table) {
    if (name == e.type) {
      Deferred<T> product = e.parse(desc, args...);
      desc.finish();
      return product;
    }
  }
  desc.fail("type", "no parser for '" + name + "'");  // unreachable: get_enum validated the type
}

}  // namespace kozu
