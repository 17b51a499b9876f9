// The scene loader's load phase (scene_loader.h): the files the parsed models need, read in parallel.
#include "scene/scene_desc.h"

#include <tbb/parallel_for.h>

#include <exception>

namespace kozu::scene_load {

// Runs every load job (files of media, meshes, environment images) in parallel; the first error in the file's
// order is thrown.
void load_all(const std::vector<std::function<void()>>& jobs) {
  std::vector<std::exception_ptr> errors(jobs.size());
  tbb::parallel_for(size_t{0}, jobs.size(), [&](size_t i) {
    try {
      jobs[i]();
    } catch (...) {
      errors[i] = std::current_exception();
    }
  });
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
}

// Load: the files every model needs, all at once.
void load_files(SceneDesc& d) {
  std::vector<std::function<void()>> jobs;
  for (Deferred<Material>& m : d.materials.models) add_load_job(m, jobs);
  for (Deferred<Medium>& m : d.media.models) add_load_job(m, jobs);
  for (ObjectDesc& o : d.objects)
    for (ShapeDesc& s : o.shapes) add_load_job(s.shape, jobs);
  for (ShapeDesc& s : d.shapes) {
    add_load_job(s.shape, jobs);
    if (s.emission_texture) add_load_job(*s.emission_texture, jobs);
    if (s.gltf) {
      jobs.emplace_back([&s, direct = d.gltf_direct] {
        try {
          // A keyed pose replaces the shape's transform under each node: meshes are then copied, not instanced.
          s.gltf->options.instance_meshes = !s.track;
          s.gltf->scene = read_gltf(s.gltf->file, s.gltf->options);
        } catch (const InputError& e) {
          if (direct) throw;  // the file is the scene: its own message says it all
          throw InputError(s.gltf->scene_name, json_pointer_append(s.json_path, "file"), e.what());
        } catch (const std::bad_alloc&) {
          throw;
        } catch (const std::exception& e) {
          throw InputError(s.gltf->file.string(), "", e.what());
        }
      });
    }
  }
  for (LightDesc& l : d.lights) add_load_job(l.light, jobs);
  load_all(jobs);
}

}  // namespace kozu::scene_load
