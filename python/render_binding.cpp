// kozu.render, kozu.load and kozu.Scene (docs/python.md): a render job (render/job.h) run in memory on a thread of
// its own while the calling thread, without the GIL, waits, reports progress and watches for Ctrl-C.
#include "bindings.h"

#include "core/file_io.h"
#include "core/load_cache.h"
#include "render/job.h"
#include "scene/scene.h"
#include "scene/scene_loader.h"

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstring>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

namespace kozu::python {

namespace {

// A scene as a dict in the scene format (docs/scene-format.md), with where its relative paths start and the files
// its renders have read (kept while unchanged, core/load_cache.h).
struct PyScene {
  py::object dict;
  std::filesystem::path base_dir;
  std::string name = "<dict>";
  std::shared_ptr<LoadCache> cache = std::make_shared<LoadCache>();
};

// One scene load at a time uses a cache (LoadCache::Scope is process-wide).
std::mutex& cached_load_mutex() {
  static std::mutex m;
  return m;
}

// What the render thread loads: a scene file as the command reads it, or JSON text.
struct SceneSource {
  std::filesystem::path file;  // empty: `text`
  std::string text, name;
  std::filesystem::path base_dir;
  std::shared_ptr<LoadCache> cache;

  std::unique_ptr<Scene> load() const {
    std::unique_lock<std::mutex> lock;
    std::optional<LoadCache::Scope> scope;
    if (cache) {
      lock = std::unique_lock(cached_load_mutex());
      scope.emplace(cache.get());
    }
    if (file.empty()) return load_scene_text(text, name, base_dir);
    const std::string ext = lower_extension(file);
    return ext == ".gltf" || ext == ".glb" ? load_gltf_file(file) : load_scene_file(file);
  }
};

SceneSource scene_source(const py::object& scene, const py::object& base_dir) {
  SceneSource s;
  if (py::isinstance<PyScene>(scene)) {
    const PyScene& ps = scene.cast<const PyScene&>();
    s.text = json_text(ps.dict);
    s.name = ps.name;
    s.base_dir = ps.base_dir;
    s.cache = ps.cache;
  } else if (py::isinstance<py::dict>(scene)) {
    s.text = json_text(scene);
    s.name = "<dict>";
    s.base_dir = base_dir_or_cwd(base_dir);
  } else {
    s.file = py::module_::import("os").attr("fspath")(scene).cast<std::string>();
    s.name = s.file.string();
  }
  return s;
}

struct RenderOptions {
  std::optional<int> spp, seed, threads, max_depth;
  std::optional<std::pair<int, int>> resolution;
  std::optional<double> time_limit;
  std::optional<std::vector<std::string>> aovs;
  bool denoise = false, verbose = false;
  std::optional<std::string> denoiser;
};

RenderJobSettings job_settings(const SceneSource& src, const RenderOptions& o) {
  RenderJobSettings s;
  s.in_memory = true;
  s.quiet = !o.verbose;
  s.scene = src.name;
  s.scene_text = src.text;
  if (o.spp) s.spp = std::to_string(*o.spp);
  if (o.seed) s.seed = std::to_string(*o.seed);
  if (o.threads) s.threads = std::to_string(*o.threads);
  if (o.max_depth) s.max_depth = std::to_string(*o.max_depth);
  if (o.time_limit) s.time_limit = std::to_string(*o.time_limit);
  if (o.resolution) s.resolution = std::to_string(o.resolution->first) + "x" + std::to_string(o.resolution->second);
  if (o.aovs && !o.aovs->empty()) {
    std::string list;
    for (const std::string& a : *o.aovs) list += (list.empty() ? "" : ",") + a;
    s.aov = list;
  }
  s.denoise = o.denoise;
  s.denoiser = o.denoiser;
  return s;
}

// The job's messages name the command's flags; the module's name its arguments.
std::string as_argument_message(std::string m) {
  static const std::pair<const char*, const char*> kNames[] = {{"kozu render: --spp", "kozu.render: spp"},
                                                               {"kozu render: --seed", "kozu.render: seed"},
                                                               {"kozu render: --threads", "kozu.render: threads"},
                                                               {"kozu render: --max-depth", "kozu.render: max_depth"},
                                                               {"kozu render: --time-limit", "kozu.render: time_limit"},
                                                               {"kozu render: --resolution", "kozu.render: resolution"},
                                                               {"kozu render: --aov", "kozu.render: aovs"},
                                                               {"kozu render: --denoiser", "kozu.render: denoiser"},
                                                               {"kozu render", "kozu.render"}};
  for (const auto& [from, to] : kNames)
    if (m.rfind(from, 0) == 0) return to + m.substr(std::strlen(from));
  return m;
}

// The render thread and what it hands back.
struct RenderRun {
  std::mutex mutex;
  std::condition_variable cv;
  bool done = false, stop = false;
  RenderJob* job = nullptr;  // while it runs (under mutex)
  std::atomic<int> signal{0};
  int status = 0;
  std::vector<std::string> errors;
  std::optional<InputError> scene_error;
  RenderImages images;

  void request_stop() {
    std::lock_guard lock(mutex);
    stop = true;
    signal = SIGINT;
    if (job) job->cancel();
  }
  double fraction() {
    std::lock_guard lock(mutex);
    return job ? job->fraction_done() : 0.0;
  }
  void run(const SceneSource& src, const RenderOptions& opt) {
    try {
      std::unique_ptr<Scene> scene = src.load();
      RenderJobHooks hooks;
      hooks.stop_signal = [this] { return signal.load(); };
      hooks.signal_name = [](int) { return std::string("KeyboardInterrupt"); };
      hooks.error = [this](const std::string& m) { errors.push_back(as_argument_message(m)); };
      RenderJob job(std::move(scene), job_settings(src, opt), hooks);
      {
        std::lock_guard lock(mutex);
        this->job = &job;
        if (stop) job.cancel();
      }
      status = job.run();
      {
        std::lock_guard lock(mutex);
        this->job = nullptr;
      }
      images = job.images();
    } catch (const InputError& e) {
      scene_error = e;
    } catch (const std::bad_alloc&) {
      errors.push_back(src.name + ": out of memory");
    } catch (const std::exception& e) {
      errors.push_back(src.name + ": " + e.what());
    }
    std::lock_guard lock(mutex);
    done = true;
    cv.notify_all();
  }
};

py::array_t<float> image_array(const std::vector<float>& values, int w, int h, int channels, size_t stride = 0,
                               size_t first = 0) {
  py::array_t<float> a({static_cast<py::ssize_t>(h), static_cast<py::ssize_t>(w), static_cast<py::ssize_t>(channels)});
  float* out = a.mutable_data();
  const size_t n = static_cast<size_t>(w) * h;
  if (stride == 0) {
    std::memcpy(out, values.data(), n * channels * sizeof(float));
    return a;
  }
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < channels; ++c) out[i * channels + c] = values[i * stride + first + c];
  return a;
}

// The AOV channels, one array per AOV under the name `aovs` takes (RenderImages::layers).
py::dict aov_arrays(const RenderImages& im) {
  py::dict out;
  size_t first = 0;
  for (const auto& [name, count] : im.layers) {
    out[py::str(name)] = image_array(im.data, im.width, im.height, count, im.channels.size(), first);
    first += static_cast<size_t>(count);
  }
  return out;
}

py::object render(const py::object& scene, const RenderOptions& opt, const py::object& progress,
                  const py::object& base_dir) {
  const SceneSource src = scene_source(scene, base_dir);
  auto run = std::make_shared<RenderRun>();
  std::thread worker;
  {
    py::gil_scoped_release nogil;
    worker = std::thread([run, src, opt] { run->run(src, opt); });
  }
  // The thread is joined on every way out of here (an exception included), after being asked to stop.
  struct Joiner {
    std::thread& t;
    RenderRun& r;
    ~Joiner() {
      if (!t.joinable()) return;
      r.request_stop();
      py::gil_scoped_release nogil;
      t.join();
    }
  } joiner{worker, *run};
  std::optional<py::error_already_set> pending;  // Ctrl-C, or the progress callback's exception
  for (bool done = false; !done;) {
    {
      py::gil_scoped_release nogil;
      std::unique_lock lock(run->mutex);
      done = run->cv.wait_for(lock, std::chrono::milliseconds(100), [&] { return run->done; });
    }
    if (pending) continue;
    try {
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
      if (!progress.is_none()) progress(done ? 1.0 : run->fraction());
    } catch (py::error_already_set& e) {
      pending.emplace(std::move(e));
      run->request_stop();
    }
  }
  {
    py::gil_scoped_release nogil;
    worker.join();
  }
  if (pending) throw std::move(*pending);
  if (run->scene_error) raise_scene_error(*run->scene_error);
  if (run->status != 0 || !run->errors.empty()) {
    std::string message;
    for (const std::string& e : run->errors) message += (message.empty() ? "" : "\n") + e;
    raise_render_error(message.empty() ? "kozu.render: the render failed" : message);
  }
  const RenderImages& im = run->images;
  py::array_t<float> rgb = image_array(im.rgb, im.width, im.height, 3);
  const bool aovs = opt.aovs && !opt.aovs->empty();
  if (!aovs) return opt.denoise ? image_array(im.denoised, im.width, im.height, 3) : rgb;
  py::dict out;
  out["rgb"] = rgb;
  if (opt.denoise) out["denoised"] = image_array(im.denoised, im.width, im.height, 3);
  for (auto item : aov_arrays(im)) out[item.first] = item.second;
  return out;
}

PyScene load(const py::object& path) {
  PyScene s;
  const std::filesystem::path file = py::module_::import("os").attr("fspath")(path).cast<std::string>();
  const std::string ext = lower_extension(file);
  if (ext == ".gltf" || ext == ".glb")
    raise_scene_error(InputError(file.string(), "",
                                 "kozu.load reads kozu scene files (.json); a glTF file is rendered with "
                                 "kozu.render(path), or placed in a scene as a {\"type\": \"gltf\"} shape"));
  std::string text;
  try {
    text = read_input_file(file);
    // A syntax error is reported the way the loader reports it, with its line.
    (void)parse_json_text(text, file.string());
  } catch (const InputError& e) {
    raise_scene_error(e);
  }
  s.dict = from_json_text(text);
  if (!py::isinstance<py::dict>(s.dict))
    raise_scene_error(InputError(file.string(), "", "a scene file holds a JSON object"));
  s.base_dir = std::filesystem::absolute(file).parent_path();
  s.name = file.string();
  return s;
}

}  // namespace

void bind_render(py::module_& m) {
  py::class_<PyScene>(
      m, "Scene",
      "A scene in kozu's format (docs/scene-format.md) as an editable dict. Rendering it again after an "
      "edit reads none of its unchanged files (meshes, voxel grids, glTF files, images) again.")
      .def(py::init([](py::dict dict, py::object base_dir) {
             PyScene s;
             s.dict = std::move(dict);
             s.base_dir = base_dir_or_cwd(base_dir);
             return s;
           }),
           py::arg("dict"), py::arg("base_dir") = py::none())
      .def_readwrite("dict", &PyScene::dict, "The scene's dict (live: edits show in the next render)")
      .def_property_readonly("base_dir", [](const PyScene& s) { return s.base_dir; })
      .def_property_readonly("name", [](const PyScene& s) { return s.name; })
      .def(
          "to_dict", [](const PyScene& s) { return py::module_::import("copy").attr("deepcopy")(s.dict); },
          "A copy of the scene's dict (kozu.Scene(scene.to_dict(), scene.base_dir) renders the same image)")
      .def(
          "cache_stats",
          [](const PyScene& s) {
            const LoadCache::Stats st = s.cache->stats();
            py::dict d;
            d["hits"] = st.hits;
            d["misses"] = st.misses;
            d["entries"] = st.entries;
            return d;
          },
          "Files read ('misses') and reused ('hits') by this scene's renders, and the number kept")
      .def(
          "clear_cache", [](PyScene& s) { s.cache->clear(); }, "Forget the files kept")
      .def("__repr__", [](const PyScene& s) { return "<kozu.Scene " + s.name + ">"; });

  m.def(
      "demo",
      [] {
        PyScene s;
        s.dict = from_json_text(std::string(demo_scene_json()));
        s.base_dir = std::filesystem::current_path();
        s.name = "<demo>";
        return s;
      },
      "The built-in demo scene (`kozu render --demo`) as a kozu.Scene");
  m.def("load", &load, py::arg("path"),
        "Reads a kozu scene file (.json) into a kozu.Scene; relative paths keep resolving against its folder");

  m.def(
      "render",
      [](const py::object& scene, std::optional<int> spp, std::optional<int> seed, std::optional<int> threads,
         std::optional<std::pair<int, int>> resolution, std::optional<double> time_limit, std::optional<int> max_depth,
         std::optional<std::vector<std::string>> aovs, bool denoise, const py::object& progress,
         const py::object& base_dir, bool verbose, std::optional<std::string> denoiser) {
        RenderOptions o{spp,   seed, threads, max_depth, resolution, time_limit, std::move(aovs), denoise,
                        verbose, std::move(denoiser)};
        return render(scene, o, progress, base_dir);
      },
      py::arg("scene"), py::arg("spp") = py::none(), py::arg("seed") = py::none(), py::arg("threads") = py::none(),
      py::arg("resolution") = py::none(), py::arg("time_limit") = py::none(), py::arg("max_depth") = py::none(),
      py::arg("aovs") = py::none(), py::arg("denoise") = false, py::arg("progress") = py::none(),
      py::arg("base_dir") = py::none(), py::arg("verbose") = false, py::arg("denoiser") = py::none(),
      "Renders a scene (a path, a dict or a kozu.Scene) and returns its linear RGB as a float32 array (H, W, 3), the "
      "pixels `kozu render` writes to its EXR; with aovs a dict of arrays. See docs/python.md.");
}

}  // namespace kozu::python
