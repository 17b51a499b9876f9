// What the binding files of the Python module share (docs/python.md): the module's exceptions, JSON between Python
// objects and kozu's parser, and numpy arrays of vectors.
#pragma once

#include "core/error.h"
#include "core/json_reader.h"
#include "core/math.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <filesystem>
#include <string>
#include <vector>

namespace kozu::python {

namespace py = pybind11;

void bind_render(py::module_& m);
void bind_models(py::module_& m);
void bind_images(py::module_& m);

// kozu.SceneError (a ValueError with .file and .json_path) and kozu.RenderError (a RuntimeError).
void define_exceptions(py::module_& m);
[[noreturn]] void raise_scene_error(const InputError& e);
[[noreturn]] void raise_render_error(const std::string& message);

// A Python object in the scene format (dicts, lists, numbers, strings) as JSON text, through Python's json module
// (a value JSON cannot hold, NaN included, raises TypeError or ValueError there); and back.
std::string json_text(const py::handle& value);
py::object from_json_text(const std::string& text);

// Relative paths of a dict resolve against base_dir, else the working directory.
std::filesystem::path base_dir_or_cwd(const py::object& base_dir);

// A (3,) or (N, 3) array of float vectors, read with numpy's conversion rules; a (3,) one broadcasts.
struct Vec3Array {
  py::array_t<float, py::array::c_style | py::array::forcecast> a;
  size_t n = 0;
  Vec3Array(const py::handle& value, const char* name);
  Vec3 operator[](size_t i) const {
    const float* p = a.data() + (n == 1 ? 0 : 3 * i);
    return Vec3(p[0], p[1], p[2]);
  }
};
// A scalar or (N,) array of floats (or (N, k) with `columns` k > 1).
struct FloatArray {
  py::array_t<float, py::array::c_style | py::array::forcecast> a;
  size_t n = 0, columns = 1;
  FloatArray(const py::handle& value, const char* name, size_t columns = 1);
  const float* operator[](size_t i) const { return a.data() + (n == 1 ? 0 : columns * i); }
};
// The common length of arrays that are each 1 or N long; ValueError naming them otherwise.
size_t broadcast_length(std::initializer_list<std::pair<const char*, size_t>> lengths);

py::array_t<float> new_array(std::vector<py::ssize_t> shape);

}  // namespace kozu::python
