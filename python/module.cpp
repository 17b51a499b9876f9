// The Python module `kozu._kozu` (docs/python.md): bindings of the render job (render/job.h), the scene loader and
// the sampled models (BSDFs, phase functions, media). python/kozu/__init__.py re-exports it.
#include "bindings.h"

#include "core/version.h"

#include <pybind11/stl.h>

#include <cstdint>
#include <stdexcept>

namespace kozu::python {

namespace {
PyObject* g_scene_error = nullptr;  // owned by the module for the interpreter's life
PyObject* g_render_error = nullptr;
}  // namespace

void define_exceptions(py::module_& m) {
  g_scene_error = PyErr_NewExceptionWithDoc(
      "kozu.SceneError",
      "A scene (a file or a dict) that kozu cannot load: str() is 'FILE: /json/path: message'; .file and "
      ".json_path name where.",
      PyExc_ValueError, nullptr);
  g_render_error = PyErr_NewExceptionWithDoc(
      "kozu.RenderError", "A render that could not run: bad settings, too little memory.", PyExc_RuntimeError, nullptr);
  m.add_object("SceneError", py::handle(g_scene_error));
  m.add_object("RenderError", py::handle(g_render_error));
}

void raise_scene_error(const InputError& e) {
  py::object error = py::reinterpret_borrow<py::object>(g_scene_error)(e.what());
  error.attr("file") = e.file();
  error.attr("json_path") = e.json_path();
  PyErr_SetObject(g_scene_error, error.ptr());
  throw py::error_already_set();
}

void raise_render_error(const std::string& message) {
  PyErr_SetString(g_render_error, message.c_str());
  throw py::error_already_set();
}

std::string json_text(const py::handle& value) {
  return py::module_::import("json").attr("dumps")(value, py::arg("allow_nan") = false).cast<std::string>();
}

py::object from_json_text(const std::string& text) { return py::module_::import("json").attr("loads")(text); }

std::filesystem::path base_dir_or_cwd(const py::object& base_dir) {
  if (base_dir.is_none()) return std::filesystem::current_path();
  return std::filesystem::path(py::module_::import("os").attr("fspath")(base_dir).cast<std::string>());
}

Vec3Array::Vec3Array(const py::handle& value, const char* name) : a(py::reinterpret_borrow<py::object>(value)) {
  if (!a) throw py::error_already_set();
  if (a.ndim() == 1 && a.shape(0) == 3)
    n = 1;
  else if (a.ndim() == 2 && a.shape(1) == 3)
    n = static_cast<size_t>(a.shape(0));
  else
    throw py::value_error(std::string(name) + ": expected an array of shape (3,) or (N, 3)");
}

FloatArray::FloatArray(const py::handle& value, const char* name, size_t k)
    : a(py::reinterpret_borrow<py::object>(value)), columns(k) {
  if (!a) throw py::error_already_set();
  if (k == 1 && a.ndim() == 0)
    n = 1;
  else if (k == 1 && a.ndim() == 1)
    n = static_cast<size_t>(a.shape(0));
  else if (k > 1 && a.ndim() == 1 && a.shape(0) == static_cast<py::ssize_t>(k))
    n = 1;
  else if (k > 1 && a.ndim() == 2 && a.shape(1) == static_cast<py::ssize_t>(k))
    n = static_cast<size_t>(a.shape(0));
  else
    throw py::value_error(std::string(name) + (k == 1 ? ": expected a number or an array of shape (N,)"
                                                      : ": expected an array of shape (" + std::to_string(k) +
                                                            ",) or (N, " + std::to_string(k) + ")"));
}

// An empty array makes n 0 (an N of 0), which every other length must then match or broadcast to.
size_t broadcast_length(std::initializer_list<std::pair<const char*, size_t>> lengths) {
  size_t n = 1;
  for (const auto& [name, len] : lengths) {
    if (len == 1 || len == n) continue;
    if (n != 1)
      throw py::value_error(std::string(name) + ": its length " + std::to_string(len) +
                            " does not match the others' (" + std::to_string(n) + ")");
    n = len;
  }
  return n;
}

py::array_t<float> new_array(std::vector<py::ssize_t> shape) { return py::array_t<float>(shape); }

}  // namespace kozu::python

PYBIND11_MODULE(_kozu, m) {
  namespace kp = kozu::python;
  m.doc() = "kozu: a physically based renderer (docs/python.md)";
  m.attr("__version__") = KOZU_VERSION;
  kp::define_exceptions(m);
  kp::bind_render(m);
  kp::bind_models(m);
  kp::bind_images(m);
}
