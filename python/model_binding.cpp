// kozu.Bsdf, kozu.Phase and kozu.Medium (docs/python.md): the renderer's sampled models, parsed from the scene
// format and evaluated and sampled over numpy arrays, in the conventions of materials/bsdf.h and media/phase.h.
#include "bindings.h"

#include "core/arena.h"
#include "core/path_budget.h"
#include "core/rng.h"
#include "geometry/ray.h"
#include "materials/material.h"
#include "media/medium.h"
#include "media/tracking.h"
#include "textures/texture_cache.h"

#include <pybind11/stl.h>

#include <memory>
#include <optional>
#include <set>
#include <string>
#include <type_traits>

namespace kozu::python {

namespace {

// The JSON of a Python description, read as the scene loader reads one at `path` of a file named `name`.
struct Description {
  Json json;
  std::shared_ptr<JsonSource> source;
  Description(const py::handle& desc, const std::string& name, const py::object& base_dir) {
    if (!py::isinstance<py::dict>(desc)) throw py::type_error(name + ": expected a dict in the scene format");
    const std::string text = json_text(desc);
    source = std::make_shared<JsonSource>(JsonSource{name, base_dir_or_cwd(base_dir)});
    try {
      json = parse_json_text(text, name);
    } catch (const InputError& e) {
      raise_scene_error(e);
    }
  }
};

// f(i, wo, wi) over the broadcast pairs of two direction arrays, without the GIL: (N,) for a float, (N, 3) for an
// Rgb.
template <class F>
py::array_t<float> map_direction_pairs(const py::object& wo_in, const py::object& wi_in, F&& f) {
  const Vec3Array wo(wo_in, "wo"), wi(wi_in, "wi");
  const size_t n = broadcast_length({{"wo", wo.n}, {"wi", wi.n}});
  using Value = decltype(f(size_t{0}, wo[0], wi[0]));
  constexpr bool rgb = std::is_same_v<Value, Rgb>;
  const auto rows = static_cast<py::ssize_t>(n);
  py::array_t<float> out = rgb ? new_array({rows, 3}) : new_array({rows});
  float* o = out.mutable_data();
  {
    py::gil_scoped_release nogil;
    for (size_t i = 0; i < n; ++i) {
      const Value v = f(i, wo[i], wi[i]);
      if constexpr (rgb)
        o[3 * i] = v.r, o[3 * i + 1] = v.g, o[3 * i + 2] = v.b;
      else
        o[i] = v;
    }
  }
  return out;
}

TransportMode transport_mode(const std::string& mode) {
  if (mode == "radiance") return TransportMode::Radiance;
  if (mode == "importance") return TransportMode::Importance;
  throw py::value_error("mode: expected 'radiance' or 'importance', got '" + mode + "'");
}

class PyBsdf {
 public:
  PyBsdf(const py::dict& desc, std::pair<float, float> uv, const py::object& base_dir) {
    Description d(desc, "<material>", base_dir);
    MaterialParseContext ctx{[this] {
      if (!textures_) textures_ = std::make_unique<TextureCache>();
      return textures_.get();
    }};
    try {
      material_ = parse_material(JsonObject(d.json, "", d.source), ctx).take();
    } catch (const InputError& e) {
      raise_scene_error(e);
    }
    // A hit at (u, v) whose shading frame is the standard basis: local directions are the BSDF's own.
    si_.p = Vec3(0.0f);
    si_.ng = Vec3(0.0f, 0.0f, 1.0f);
    si_.shading = Frame(si_.ng);
    si_.uv = Vec2(uv.first, uv.second);
    si_.wo = si_.ng;
    bsdf_ = material_->bsdf(si_, arena_);
  }

  py::array_t<float> eval(const py::object& wo_in, const py::object& wi_in, const std::string& mode_name) const {
    const TransportMode mode = transport_mode(mode_name);
    return map_direction_pairs(wo_in, wi_in,
                               [&](size_t, const Vec3& wo, const Vec3& wi) { return bsdf_->eval(wo, wi, mode); });
  }

  py::array_t<float> pdf(const py::object& wo_in, const py::object& wi_in) const {
    return map_direction_pairs(wo_in, wi_in,
                               [&](size_t, const Vec3& wo, const Vec3& wi) { return bsdf_->pdf(wo, wi); });
  }

  py::tuple sample(const py::object& wo_in, const py::object& u_lobe_in, const py::object& u_in,
                   const std::string& mode_name) const {
    const TransportMode mode = transport_mode(mode_name);
    const Vec3Array wo(wo_in, "wo");
    const FloatArray u_lobe(u_lobe_in, "u_lobe"), u(u_in, "u", 2);
    const size_t n = broadcast_length({{"wo", wo.n}, {"u_lobe", u_lobe.n}, {"u", u.n}});
    py::array_t<float> wi = new_array({static_cast<py::ssize_t>(n), 3});
    py::array_t<float> weight = new_array({static_cast<py::ssize_t>(n), 3});
    py::array_t<float> pdf = new_array({static_cast<py::ssize_t>(n)});
    float *w = wi.mutable_data(), *f = weight.mutable_data(), *p = pdf.mutable_data();
    {
      py::gil_scoped_release nogil;
      for (size_t i = 0; i < n; ++i) {
        const BsdfSample s = bsdf_->sample(wo[i], u_lobe[i][0], Vec2(u[i][0], u[i][1]), mode);
        const Rgb wt = s.valid() ? s.weight() : Rgb(0.0f);
        const Vec3 d = s.valid() ? s.wi : Vec3(0.0f);
        w[3 * i] = d.x, w[3 * i + 1] = d.y, w[3 * i + 2] = d.z;
        f[3 * i] = wt.r, f[3 * i + 1] = wt.g, f[3 * i + 2] = wt.b;
        p[i] = s.valid() ? s.pdf : 0.0f;
      }
    }
    return py::make_tuple(wi, weight, pdf);
  }

  std::set<std::string> flags() const {
    std::set<std::string> out;
    const uint32_t f = bsdf_->flags();
    for (const auto& [bit, name] : {std::pair{kBsdfReflection, "reflection"},
                                    {kBsdfTransmission, "transmission"},
                                    {kBsdfDiffuse, "diffuse"},
                                    {kBsdfGlossy, "glossy"},
                                    {kBsdfSpecular, "specular"}})
      if (f & bit) out.insert(name);
    return out;
  }

 private:
  std::unique_ptr<TextureCache> textures_;
  std::unique_ptr<Material> material_;
  SurfaceInteraction si_;
  Arena arena_;
  const Bsdf* bsdf_ = nullptr;
};

// Stochastic models (the SGGX diffuse phase function, ratio tracking) draw element i's numbers from stream i of
// the seed: an element's value does not depend on the array it is in.
Pcg32 element_rng(uint64_t seed, size_t i) { return Pcg32(seed, i); }

class PyMedium;

class PyPhase {
 public:
  PyPhase(std::shared_ptr<const Medium> medium, const Vec3& p)
      : medium_(std::move(medium)), arena_(std::make_unique<Arena>()) {
    phase_ = medium_->phase(p, *arena_);
  }
  static PyPhase from_description(const py::dict& desc, const py::object& point);

  py::array_t<float> eval(const py::object& wo_in, const py::object& wi_in, uint64_t seed) const {
    return map_direction_pairs(wo_in, wi_in, [&](size_t i, const Vec3& wo, const Vec3& wi) {
      Pcg32 rng = element_rng(seed, i);
      return phase_->eval(wo, wi, rng);
    });
  }
  py::array_t<float> pdf(const py::object& wo_in, const py::object& wi_in) const {
    return map_direction_pairs(wo_in, wi_in,
                               [&](size_t, const Vec3& wo, const Vec3& wi) { return phase_->pdf(wo, wi); });
  }
  py::tuple sample(const py::object& wo_in, const py::object& u_in, uint64_t seed) const {
    const Vec3Array wo(wo_in, "wo");
    const FloatArray u(u_in, "u", 2);
    const size_t n = broadcast_length({{"wo", wo.n}, {"u", u.n}});
    py::array_t<float> wi = new_array({static_cast<py::ssize_t>(n), 3});
    py::array_t<float> weight = new_array({static_cast<py::ssize_t>(n)});
    py::array_t<float> pdf = new_array({static_cast<py::ssize_t>(n)});
    float *w = wi.mutable_data(), *f = weight.mutable_data(), *p = pdf.mutable_data();
    {
      py::gil_scoped_release nogil;
      for (size_t i = 0; i < n; ++i) {
        Pcg32 rng = element_rng(seed, i);
        const PhaseSample s = phase_->sample(wo[i], Vec2(u[i][0], u[i][1]), rng);
        const Vec3 d = s.valid() ? s.wi : Vec3(0.0f);
        w[3 * i] = d.x, w[3 * i + 1] = d.y, w[3 * i + 2] = d.z;
        f[i] = s.valid() ? s.weight() : 0.0f;
        p[i] = s.valid() ? s.pdf : 0.0f;
      }
    }
    return py::make_tuple(wi, weight, pdf);
  }

 private:
  std::shared_ptr<const Medium> medium_;  // owns the phase function (or its parameters)
  std::unique_ptr<Arena> arena_;          // holds a phase function made for the point
  const PhaseFunction* phase_ = nullptr;
};

std::shared_ptr<const Medium> parse_medium_dict(const py::dict& desc, const py::object& base_dir) {
  Description d(desc, "<medium>", base_dir);
  try {
    return std::shared_ptr<const Medium>(parse_medium(JsonObject(d.json, "", d.source)).take());
  } catch (const InputError& e) {
    raise_scene_error(e);
  }
}

class PyMedium {
 public:
  PyMedium(const py::dict& desc, const py::object& base_dir) : medium_(parse_medium_dict(desc, base_dir)) {}

  py::tuple properties(const py::object& p_in, const py::object& d_in) const {
    const Vec3Array p(p_in, "p"), d(d_in, "d");
    const size_t n = broadcast_length({{"p", p.n}, {"d", d.n}});
    py::array_t<float> st = new_array({static_cast<py::ssize_t>(n), 3});
    py::array_t<float> ss = new_array({static_cast<py::ssize_t>(n), 3});
    float *t = st.mutable_data(), *s = ss.mutable_data();
    {
      py::gil_scoped_release nogil;
      for (size_t i = 0; i < n; ++i) {
        const MediumProperties m = medium_->properties(p[i], d[i]);
        t[3 * i] = m.sigma_t.r, t[3 * i + 1] = m.sigma_t.g, t[3 * i + 2] = m.sigma_t.b;
        s[3 * i] = m.sigma_s.r, s[3 * i + 1] = m.sigma_s.g, s[3 * i + 2] = m.sigma_s.b;
      }
    }
    return py::make_tuple(st, ss);
  }

  py::array_t<float> transmittance(const py::object& o_in, const py::object& d_in, const py::object& t_in,
                                   uint64_t seed) const {
    const Vec3Array o(o_in, "o"), d(d_in, "d");
    const FloatArray t(t_in, "t");
    const size_t n = broadcast_length({{"o", o.n}, {"d", d.n}, {"t", t.n}});
    py::array_t<float> out = new_array({static_cast<py::ssize_t>(n), 3});
    float* tr = out.mutable_data();
    {
      py::gil_scoped_release nogil;
      for (size_t i = 0; i < n; ++i) {
        Pcg32 rng = element_rng(seed, i);
        PathBudget budget;
        const Rgb v = ratio_tracking(*medium_, Ray{o[i], normalize(d[i])}, t[i][0], rng, budget);
        tr[3 * i] = v.r, tr[3 * i + 1] = v.g, tr[3 * i + 2] = v.b;
      }
    }
    return out;
  }

  PyPhase phase(const py::object& point) const { return PyPhase(medium_, Vec3Array(point, "point")[0]); }

 private:
  std::shared_ptr<const Medium> medium_;
};

// {"type": "hg", "g": g} and {"type": "isotropic"} are the phase functions of a homogeneous medium; any other
// description is a medium's, whose phase function at `point` it is.
PyPhase PyPhase::from_description(const py::dict& desc, const py::object& point) {
  const Vec3 p = Vec3Array(point, "point")[0];
  const std::string type = desc.contains("type") ? py::str(desc["type"]).cast<std::string>() : "";
  if (type == "hg" || type == "isotropic") {
    py::dict medium;
    medium["type"] = "homogeneous";
    medium["phase"] = type == "hg" ? py::object(desc) : py::object(py::str("isotropic"));
    if (type == "isotropic" && py::len(desc) > 1)
      throw py::value_error("kozu.Phase: an isotropic phase function takes no parameters");
    return PyPhase(parse_medium_dict(medium, py::none()), p);
  }
  return PyPhase(parse_medium_dict(desc, py::none()), p);
}

}  // namespace

void bind_models(py::module_& m) {
  py::class_<PyBsdf>(m, "Bsdf",
                     "A material's BSDF at one point of a surface, in its local shading frame (normal +z), with "
                     "materials/bsdf.h's conventions: eval is f·|cos θi|, wo points towards the viewer.")
      .def(py::init<const py::dict&, std::pair<float, float>, const py::object&>(), py::arg("material"),
           py::arg("uv") = std::pair<float, float>(0.5f, 0.5f), py::arg("base_dir") = py::none())
      .def("eval", &PyBsdf::eval, py::arg("wo"), py::arg("wi"), py::arg("mode") = "radiance",
           "f(wo, wi)·|cos θi|, shape (N, 3)")
      .def("pdf", &PyBsdf::pdf, py::arg("wo"), py::arg("wi"), "The density of sample's wi per solid angle, (N,)")
      .def("sample", &PyBsdf::sample, py::arg("wo"), py::arg("u_lobe"), py::arg("u"), py::arg("mode") = "radiance",
           "(wi (N, 3), weight = f·|cos θi| / pdf (N, 3), pdf (N,)); pdf 0 where no direction was sampled")
      .def_property_readonly("flags", &PyBsdf::flags,
                             "Its lobes: reflection, transmission, diffuse, glossy, specular (a Dirac delta)");
  py::class_<PyPhase>(m, "Phase",
                      "A phase function, with media/phase.h's conventions: world-space directions, eval is f_p per "
                      "solid angle (no cosine), wo points towards the previous vertex.")
      .def(py::init(&PyPhase::from_description), py::arg("desc"),
           py::arg("point") = std::vector<float>{0.0f, 0.0f, 0.0f})
      .def("eval", &PyPhase::eval, py::arg("wo"), py::arg("wi"), py::arg("seed") = 0,
           "f_p(wo, wi), (N,) (an unbiased estimate for stochastic phase functions: the SGGX diffuse one)")
      .def("pdf", &PyPhase::pdf, py::arg("wo"), py::arg("wi"))
      .def("sample", &PyPhase::sample, py::arg("wo"), py::arg("u"), py::arg("seed") = 0,
           "(wi (N, 3), weight = f / pdf (N,), pdf (N,))");
  py::class_<PyMedium>(m, "Medium", "A participating medium described as in a scene's \"media\" (docs/volumes.md)")
      .def(py::init<const py::dict&, const py::object&>(), py::arg("desc"), py::arg("base_dir") = py::none())
      .def("properties", &PyMedium::properties, py::arg("p"), py::arg("d"),
           "(sigma_t (N, 3), sigma_s (N, 3)) at points p for light along directions d")
      .def("transmittance", &PyMedium::transmittance, py::arg("o"), py::arg("d"), py::arg("t"), py::arg("seed") = 0,
           "Ratio-tracking estimates of the transmittance over [0, t] of the rays o + s d, (N, 3): unbiased, exact "
           "for a homogeneous medium")
      .def("phase", &PyMedium::phase, py::arg("point") = std::vector<float>{0.0f, 0.0f, 0.0f});
}

}  // namespace kozu::python
