// The scene loader's glTF expansion (scene_loader.h): each loaded glTF file's meshes, materials, media and
// lights turned into the scene's own descriptions; the camera of a glTF file rendered directly.
#include "scene/scene_desc.h"

#include "geometry/mesh_cleanup.h"

#include <algorithm>
#include <cmath>

namespace kozu::scene_load {

namespace {

using GltfFiles = std::vector<std::shared_ptr<GltfDesc>>;
using MeshDesc = std::function<bool(GltfPrimitive&, ShapeDesc&)>;

// Runs f, a message about a glTF's kozu description turned into one naming the glTF's own JSON path.
void in_gltf_terms(const GltfFiles& files, const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    for (const auto& g : files)
      if (e.file() == g->file.string()) {
        const std::string prefix = InputError::format(e.file(), e.json_path(), "");
        const std::string what = e.what();
        throw InputError(e.file(), g->scene.gltf_path(e.json_path()),
                         what.rfind(prefix, 0) == 0 ? what.substr(prefix.size()) : what);
      }
    throw;
  }
}

// Meshes several nodes use (never emitting ones: GltfScene::objects): stored once, placed by instances. An instance
// counts as one triangle in `triangles`, with mesh_desc's.
void expand_gltf_objects(SceneDesc& d, GltfScene& g, const ShapeDesc& sd, const MeshDesc& mesh_desc,
                         std::vector<ShapeDesc>& shapes, size_t& triangles) {
  const std::filesystem::path& file = sd.gltf->file;
  std::vector<std::optional<size_t>> object_index(g.objects.size());
  std::vector<std::pair<Vec3, Vec3>> object_bounds(g.objects.size(), {Vec3(kInfinity), Vec3(-kInfinity)});
  for (size_t o = 0; o < g.objects.size(); ++o) {
    ObjectDesc object;
    const size_t before = triangles;
    for (GltfPrimitive& p : g.objects[o].primitives) {
      for (const Vec3& v : p.mesh.positions) {
        object_bounds[o].first = glm::min(object_bounds[o].first, v);
        object_bounds[o].second = glm::max(object_bounds[o].second, v);
      }
      ShapeDesc s;
      if (mesh_desc(p, s)) object.shapes.push_back(std::move(s));
    }
    triangles = before;  // counted by its instances below
    if (object.shapes.empty()) continue;
    object_index[o] = d.objects.size();
    d.object_names.push_back(file.filename().string() + ":" + g.objects[o].name);
    d.objects.push_back(std::move(object));
  }
  for (const GltfInstance& inst : g.instances) {
    if (!object_index[inst.object]) continue;
    ++triangles;  // the object holds triangles (empty ones were left out): enough to know something is drawn
    const auto& [lo, hi] = object_bounds[inst.object];
    for (int c = 0; c < 8; ++c) {
      const Vec3 w(inst.transform * Vec4(c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z, 1.0f));
      d.lo = glm::min(d.lo, w);
      d.hi = glm::max(d.hi, w);
    }
    ShapeDesc s;
    s.type = "instance";
    s.json_path = sd.json_path + inst.json_path;
    s.object = object_index[inst.object];
    s.name = sd.name;
    s.file = sd.file;
    s.placement = inst.transform;
    shapes.push_back(std::move(s));
  }
}

// One "gltf" shape, its file loaded: its materials, media, meshes, objects and lights as the scene's own
// descriptions (its shapes appended to `shapes`). `files` are the glTF files so far, this one last.
void expand_gltf_file(SceneDesc& d, ShapeDesc& sd, const GltfFiles& files, std::vector<ShapeDesc>& shapes) {
  GltfScene& g = sd.gltf->scene;
  const std::filesystem::path& file = sd.gltf->file;
  auto src = std::make_shared<JsonSource>(JsonSource{file.string(), file.parent_path()});
  src->files = g.input_files;
  d.sources.push_back(src);
  for (const std::string& w : g.warnings) d.warnings.push_back(w);
  const size_t material_base = d.materials.models.size();
  in_gltf_terms(files, [&] {
    for (size_t i = 0; i < g.materials.size(); ++i) {
      Json& m = g.materials[i];
      d.materials.models.push_back(parse_material(JsonObject(m, fmt::format("/materials/{}", i), src), d.material_ctx));
      d.materials.names.push_back(file.filename().string() + ":" + g.material_names[i]);
    }
  });
  std::vector<std::optional<size_t>> interior(g.media.size());
  in_gltf_terms(files, [&] {
    for (size_t i = 0; i < g.media.size(); ++i) {
      if (g.media[i].is_null()) continue;
      interior[i] = d.media.models.size();
      d.media.models.push_back(
          parse_medium(JsonObject(g.media[i], fmt::format("/materials/{}/extensions/KHR_materials_volume", i), src)));
      d.media.names.push_back(file.filename().string() + ":" + g.material_names[i]);
    }
  });
  size_t triangles = 0;
  // A primitive as a mesh shape (degenerate triangles dropped); false when nothing is left of it.
  const auto mesh_desc = [&](GltfPrimitive& p, ShapeDesc& s) {
    MeshData& mesh = p.mesh;
    // Zero-area triangles are common in exported assets and invisible: dropped.
    remove_degenerate_triangles(mesh);
    if (mesh.indices.empty()) return false;
    triangles += mesh.indices.size() / 3;
    s.type = "mesh";
    s.json_path = sd.json_path + p.json_path;
    s.material = material_base + size_t(p.material);
    s.interior = interior[size_t(p.material)];
    s.file = sd.file;
    s.shape = std::make_unique<TriangleMesh>(std::move(mesh.positions), std::move(mesh.indices),
                                             std::move(mesh.normals), std::move(mesh.uvs), std::move(mesh.tangents));
    return true;
  };
  for (GltfPrimitive& p : g.primitives) {
    for (const Vec3& v : p.mesh.positions) {
      d.lo = glm::min(d.lo, v);
      d.hi = glm::max(d.hi, v);
    }
    ShapeDesc s;
    if (!mesh_desc(p, s)) continue;
    s.emission = g.emission[size_t(p.material)];
    s.two_sided = g.double_sided[size_t(p.material)];
    s.name = sd.name;
    s.placement = sd.placement;
    s.track = sd.track;
    shapes.push_back(std::move(s));
  }
  expand_gltf_objects(d, g, sd, mesh_desc, shapes, triangles);
  // A file that yields nothing to see is an error, not an empty image.
  if (triangles == 0 && (d.gltf_direct || g.lights.empty()))
    throw InputError(file.string(), "",
                     "the file yields no triangle to render (its scene's meshes are missing, points or lines only, "
                     "or of zero area)");
  for (size_t i = 0; i < g.lights.size(); ++i) {
    const std::string path = g.gltf_path(fmt::format("/lights/{}", i));
    in_gltf_terms(files, [&] {
      d.lights.push_back({fmt::format("{}: {}", file.string(), path),
                          parse_light(JsonObject(g.lights[i], fmt::format("/lights/{}", i), src))});
    });
    ++d.gltf_lights;
  }
  if (g.camera && !d.gltf_camera) d.gltf_camera = g.camera;
}

}  // namespace

// The shapes, materials, media and lights of each glTF file (after load_files): parsed as kozu descriptions whose
// messages name the glTF file and its own JSON paths (GltfScene::gltf_path), and their textures prepared in
// parallel. A mesh several nodes use becomes one of the scene's objects, placed by instances. The files the glTF
// reads (buffers, images) are inputs of the render.
void expand_gltf(SceneDesc& d) {
  std::vector<ShapeDesc> shapes;
  std::vector<std::function<void()>> jobs;
  GltfFiles files;
  const size_t first_material = d.materials.models.size(), first_light = d.lights.size();
  for (ShapeDesc& sd : d.shapes) {
    if (!sd.gltf) {
      shapes.push_back(std::move(sd));
      continue;
    }
    files.push_back(sd.gltf);
    expand_gltf_file(d, sd, files, shapes);
  }
  d.shapes = std::move(shapes);
  for (size_t i = first_material; i < d.materials.models.size(); ++i) add_load_job(d.materials.models[i], jobs);
  for (size_t i = first_light; i < d.lights.size(); ++i) add_load_job(d.lights[i].light, jobs);
  in_gltf_terms(files, [&] { load_all(jobs); });
}

// The camera of a glTF file rendered directly: the file's first perspective camera, or one that frames the
// meshes' bounds from a three-quarter view (35° round from +z towards +x, 25° up), the bounding sphere filling
// the vertical field of view.
Camera gltf_direct_camera(const SceneDesc& d) {
  const Vec2i res(1280, 720);
  if (d.gltf_camera) {
    const GltfCamera& c = *d.gltf_camera;
    Vec2i r = res;
    if (c.aspect > 0.0f) r.x = std::clamp(static_cast<int>(std::lround(720.0f * c.aspect)), 1, 65536);
    return Camera(c.position, c.position + c.forward, c.up, c.yfov_degrees, r);
  }
  Vec3 center(0.0f);
  float radius = 1.0f;
  if (d.lo.x <= d.hi.x) {
    center = 0.5f * (d.lo + d.hi);
    radius = std::max(0.5f * glm::length(d.hi - d.lo), 1e-6f);
  }
  const float fov = 40.0f, azimuth = glm::radians(35.0f), elevation = glm::radians(25.0f);
  const Vec3 dir(std::cos(elevation) * std::sin(azimuth), std::sin(elevation), std::cos(elevation) * std::cos(azimuth));
  const float distance = radius / std::sin(glm::radians(fov / 2.0f));
  return Camera(center + distance * dir, center, Vec3(0, 1, 0), fov, res);
}

}  // namespace kozu::scene_load
