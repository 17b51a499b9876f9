// kozu.read_image and kozu.write_image (docs/python.md): image files through the renderer's own readers and
// writers (io/image_io.h), so that a render from Python and the CLI's EXR compare exactly.
#include "bindings.h"

#include "io/image_io.h"

#include <pybind11/stl.h>

#include <cstring>
#include <filesystem>

namespace kozu::python {

namespace {

py::object read(const py::object& path, bool names) {
  const std::string file = py::module_::import("os").attr("fspath")(path).cast<std::string>();
  Image img;
  try {
    py::gil_scoped_release nogil;
    img = read_image_all(file);
  } catch (const InputError& e) {
    raise_scene_error(e);
  }
  py::array_t<float> out = new_array({img.height, img.width, img.channels});
  std::memcpy(out.mutable_data(), img.data.data(), img.data.size() * sizeof(float));
  if (!names) return out;
  return py::make_tuple(out, py::cast(img.channel_names));
}

void write(const py::object& path, const py::object& image, const std::string& tonemap, float exposure) {
  const std::string file = py::module_::import("os").attr("fspath")(path).cast<std::string>();
  const py::array_t<float, py::array::c_style | py::array::forcecast> a(image);
  if (a.ndim() != 3 || a.shape(2) != 3 || a.shape(0) < 1 || a.shape(1) < 1)
    throw py::value_error("kozu.write_image: expected an image of shape (H, W, 3)");
  ToneMap tm;
  try {
    tm.curve = ToneMap::parse(tonemap);
  } catch (const std::invalid_argument& e) {
    throw py::value_error(std::string("kozu.write_image: tonemap: ") + e.what());
  }
  tm.exposure = exposure;
  std::vector<float> rgb(a.data(), a.data() + a.size());
  const int w = static_cast<int>(a.shape(1)), h = static_cast<int>(a.shape(0));
  try {
    py::gil_scoped_release nogil;
    // As the command does with its outputs, the folder is made when missing.
    const std::filesystem::path parent = std::filesystem::path(file).parent_path();
    if (!parent.empty()) std::filesystem::create_directories(parent);
    write_image(file, w, h, rgb, tm);
  } catch (const std::exception& e) {
    raise_render_error(e.what());
  }
}

}  // namespace

void bind_images(py::module_& m) {
  m.def("read_image", &read, py::arg("path"), py::kw_only(), py::arg("names") = false,
        "An image file's pixels as float32 (H, W, C), every channel (8-bit files scaled to [0, 1], not "
        "linearised); with names=True also the channels' names ('R', 'G', 'B', 'albedo.R', ...)");
  m.def("write_image", &write, py::arg("path"), py::arg("image"), py::kw_only(), py::arg("tonemap") = "aces",
        py::arg("exposure") = 0.0f,
        "Writes linear RGB (H, W, 3) as kozu render does: .exr/.hdr as float, .png/.jpg tone-mapped to sRGB, "
        "through a temporary file renamed into place");
}

}  // namespace kozu::python
