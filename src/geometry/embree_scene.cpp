#include "geometry/embree_scene.h"

#include "core/error.h"
#include "core/memory.h"
#include "core/rng.h"

#include <fmt/format.h>

#include <cmath>
#include <cstring>
#include <stdexcept>
#include <unordered_set>

namespace kozu {

namespace {
// Exceptions must not cross Embree's C frames: the callback records, the caller checks.
thread_local std::string embree_last_error;
void embree_error(void*, RTCError code, const char* message) {
  embree_last_error = fmt::format("Embree error {}: {}", static_cast<int>(code), message ? message : "");
}
void check(RTCDevice device) {
  if (rtcGetDeviceError(device) != RTC_ERROR_NONE) throw std::runtime_error(embree_last_error);
}

// Embree requires origin and direction components within ±1.844e18 and a t range that is not NaN (its
// RayK::valid(), asserted in Debian's build): a NaN that reached a ray would abort the process. Such a ray hits
// nothing (and a shadow ray counts as blocked); its sample becomes non-finite and is discarded and counted.
bool valid_for_embree(const Ray& r, float tnear) {
  constexpr float kLarge = 1.844e18f;
  const auto ok = [&](const Vec3& v) {
    return std::abs(v.x) <= kLarge && std::abs(v.y) <= kLarge && std::abs(v.z) <= kLarge;
  };
  return ok(r.o) && ok(r.d) && tnear >= 0.0f && !std::isnan(r.tmax);
}

uint32_t float_bits(float x) {
  uint32_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

// Opacity cut-outs (Shape::opacity, materials/opacity_mask.h), run by Embree on every candidate hit of a shape
// that has one, for closest-hit and any-hit queries alike. A fractional opacity keeps the hit with that
// probability, decided by a hash of the ray (origin, direction), the geometry, the primitive and the hit distance:
// deterministic for a given ray (a ray always sees the same holes, whichever query traces it, on any thread) and
// independent between rays.
void opacity_filter(const RTCFilterFunctionNArguments* args) {
  const auto* shape = static_cast<const Shape*>(args->geometryUserPtr);
  const unsigned n = args->N;
  for (unsigned i = 0; i < n; ++i) {
    if (args->valid[i] != -1) continue;
    const Vec3 o(RTCRayN_org_x(args->ray, n, i), RTCRayN_org_y(args->ray, n, i), RTCRayN_org_z(args->ray, n, i));
    const Vec3 d(RTCRayN_dir_x(args->ray, n, i), RTCRayN_dir_y(args->ray, n, i), RTCRayN_dir_z(args->ray, n, i));
    const float t = RTCRayN_tfar(args->ray, n, i);  // the candidate's distance while the filter runs
    const uint32_t prim = RTCHitN_primID(args->hit, n, i);
    const float alpha = shape->opacity->opacity(
        shape->hit_uv(Ray{o, d, kInfinity}, t, prim, RTCHitN_u(args->hit, n, i), RTCHitN_v(args->hit, n, i)));
    if (alpha >= 1.0f) continue;
    uint32_t h = hash_u32(RTCHitN_geomID(args->hit, n, i));
    for (const uint32_t v : {float_bits(o.x), float_bits(o.y), float_bits(o.z), float_bits(d.x), float_bits(d.y),
                             float_bits(d.z), float_bits(t), prim})
      h = hash_combine(h, v);
    if (!(alpha > 0.0f) || u32_to_unit_float(hash_u32(h)) >= alpha) args->valid[i] = 0;
  }
}

// Installs opacity_filter on the geometry `id` of `shape`.
void install_opacity_filter(RTCDevice device, RTCScene scene, unsigned id, const Shape* shape) {
  if (!rtcGetDeviceProperty(device, RTC_DEVICE_PROPERTY_FILTER_FUNCTION_SUPPORTED))
    throw std::runtime_error("this Embree build has no filter functions: opacity cut-outs are not available");
  RTCGeometry geom = rtcGetGeometry(scene, id);
  rtcSetGeometryUserData(geom, const_cast<Shape*>(shape));
  rtcSetGeometryIntersectFilterFunction(geom, &opacity_filter);
  rtcSetGeometryOccludedFilterFunction(geom, &opacity_filter);
  rtcCommitGeometry(geom);
}

// Memory of the hierarchy, measured with the peak resident memory during rtcCommitScene (VmHWM, reset through
// /proc/self/clear_refs just before it) of `kozu render` on generated grids (Embree 3.13, high-quality build,
// 2 threads): 92 bytes a triangle for 0.5 M triangles, 98 for 2 M (58 of them kept after the build); and for
// 10^5 instances of one 4,880-triangle object, 211 bytes an instance for its Embree geometry and 140 more during
// the top-level build. kozu's own per-triangle data (positions, indices, normals, uvs, tangents) is already
// resident when the hierarchy is built, so the check compares these with what is left.
constexpr double kEmbreeBytesPerPrimitive = 100;
constexpr double kEmbreeBytesPerInstance = 400;
// An instance from its creation on: kozu's Instance (352 bytes) and its name, plus its Embree part. (The 2.3 KB an
// instance costs in a whole render, docs/scene-format.md, is mostly the scene file's parsed JSON, resident by then.)
constexpr double kInstanceBytes = 800;

double memory_left(MemoryLimit* limit) {
  *limit = memory_limit();
  return std::max(0.0, memory_left(*limit));
}
}  // namespace

void check_instance_memory(size_t instances, const std::string& file, const std::string& json_path) {
  MemoryLimit limit;
  const double left = memory_left(&limit), need = kInstanceBytes * double(instances);
  if (need > left)
    throw InputError(
        file, json_path,
        fmt::format("the scene's {} instances need about {} but only {} of the {} limit ({}) is left", instances,
                    format_bytes(need), format_bytes(left), format_bytes(double(limit.bytes)), limit.source));
}

namespace {
// Throws when the hierarchy over `shapes` cannot fit (each instanced object's own hierarchy counted once).
void check_hierarchy_memory(const std::vector<std::unique_ptr<Shape>>& shapes) {
  double primitives = 0, instances = 0;
  std::unordered_set<const InstancedObject*> objects;
  for (const auto& s : shapes) {
    if (const auto* inst = dynamic_cast<const Instance*>(s.get())) {
      ++instances;
      if (objects.insert(&inst->object()).second)
        for (const auto& o : inst->object().shapes()) primitives += double(o->primitive_count());
    } else {
      primitives += double(s->primitive_count());
    }
  }
  MemoryLimit limit;
  const double left = memory_left(&limit);
  const double need = kEmbreeBytesPerPrimitive * primitives + kEmbreeBytesPerInstance * instances;
  if (need > left)
    throw std::runtime_error(fmt::format(
        "the scene's acceleration structure needs about {} ({:.0f} primitives, {:.0f} instances) but only {} of the "
        "{} limit ({}) is left",
        format_bytes(need), primitives, instances, format_bytes(left), format_bytes(double(limit.bytes)),
        limit.source));
}
}  // namespace

RTCDevice make_embree_device() {
  RTCDevice device = rtcNewDevice("verbose=0");
  if (!device)
    throw std::runtime_error(
        fmt::format("cannot create Embree device (error {})", static_cast<int>(rtcGetDeviceError(nullptr))));
  rtcSetDeviceErrorFunction(device, embree_error, nullptr);
  return device;
}

unsigned attach_shape(RTCDevice device, RTCScene scene, const Shape& shape) {
  const unsigned id = shape.attach(device, scene);
  check(device);
  if (shape.opacity) {
    install_opacity_filter(device, scene, id, &shape);
    check(device);
  }
  return id;
}

EmbreeScene::EmbreeScene(const std::vector<std::unique_ptr<Shape>>& shapes) {
  check_hierarchy_memory(shapes);
  device_ = make_embree_device();
  try {
    scene_ = rtcNewScene(device_);
    check(device_);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
    rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_NONE);
    for (const auto& s : shapes) {
      hidden_from_camera_ = hidden_from_camera_ || !s->camera_visible;
      const unsigned id = attach_shape(device_, scene_, *s);
      if (id >= by_geom_id_.size()) {
        by_geom_id_.resize(id + 1, nullptr);
        instances_.resize(id + 1, nullptr);
      }
      by_geom_id_[id] = s.get();
      instances_[id] = dynamic_cast<const Instance*>(s.get());
    }
    rtcCommitScene(scene_);
    check(device_);
  } catch (...) {
    if (scene_) rtcReleaseScene(scene_);
    rtcReleaseDevice(device_);
    throw;
  }
}

void EmbreeScene::update(const std::vector<const Shape*>& moved) {
  const std::unordered_set<const Shape*> set(moved.begin(), moved.end());
  for (unsigned id = 0; id < by_geom_id_.size(); ++id)
    if (set.count(by_geom_id_[id])) by_geom_id_[id]->refresh(rtcGetGeometry(scene_, id));
  rtcCommitScene(scene_);
  check(device_);
}

EmbreeScene::~EmbreeScene() {
  if (scene_) rtcReleaseScene(scene_);
  if (device_) rtcReleaseDevice(device_);
}

bool EmbreeScene::intersect(const Ray& ray, SurfaceInteraction& si) const {
  if (log_ && (log_->limit == 0 || log_->closest.size() < log_->limit)) [[unlikely]]
    log_->closest.push_back(ray);
  return intersect_from(ray, 0.0f, si) != RTC_INVALID_GEOMETRY_ID;
}

bool EmbreeScene::intersect_camera(const Ray& ray, SurfaceInteraction& si) const {
  if (!intersect(ray, si)) return false;
  while (!si.shape->camera_visible) {
    // Step just past the hidden shape, as intersect_shape does.
    const float tnear = std::nextafter(si.t, kInfinity) + 1e-7f * si.t;
    if (intersect_from(ray, tnear, si) == RTC_INVALID_GEOMETRY_ID) return false;
  }
  return true;
}

unsigned EmbreeScene::intersect_from(const Ray& ray, float tnear, SurfaceInteraction& si) const {
  if (!valid_for_embree(ray, tnear)) [[unlikely]]
    return RTC_INVALID_GEOMETRY_ID;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh;
  rh.ray.org_x = ray.o.x;
  rh.ray.org_y = ray.o.y;
  rh.ray.org_z = ray.o.z;
  rh.ray.dir_x = ray.d.x;
  rh.ray.dir_y = ray.d.y;
  rh.ray.dir_z = ray.d.z;
  rh.ray.tnear = tnear;
  rh.ray.tfar = ray.tmax;
  rh.ray.time = 0.0f;
  rh.ray.mask = 0xffffffffu;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(scene_, &ctx, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return RTC_INVALID_GEOMETRY_ID;
  const Vec3 ng(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
  if (const unsigned inst = rh.hit.instID[0]; inst != RTC_INVALID_GEOMETRY_ID) {
    // geomID and primID are the object's; Ng is in object space.
    instances_[inst]->instanced_interaction(ray, rh.ray.tfar, rh.hit.geomID, rh.hit.primID, rh.hit.u, rh.hit.v, ng, si);
    return inst;
  }
  by_geom_id_[rh.hit.geomID]->interaction(ray, rh.ray.tfar, rh.hit.primID, rh.hit.u, rh.hit.v, ng, si);
  si.instance = nullptr;
  return rh.hit.geomID;
}

int EmbreeScene::intersect_shape(const Ray& ray, const Shape* shape, const Instance* instance, SurfaceInteraction* hits,
                                 int max_hits, uint64_t* rays) const {
  int n = 0;
  float tnear = 0.0f;
  while (n < max_hits) {
    SurfaceInteraction si;
    ++*rays;
    if (intersect_from(ray, tnear, si) == RTC_INVALID_GEOMETRY_ID) break;
    // Step just past this hit: Embree reports t >= tnear, and the same primitive returns the same t.
    tnear = std::nextafter(si.t, kInfinity) + 1e-7f * si.t;
    if (si.shape == shape && si.instance == instance) hits[n++] = si;
  }
  return n;
}

bool EmbreeScene::occluded(const Ray& ray) const {
  if (log_ && (log_->limit == 0 || log_->shadow.size() < log_->limit)) [[unlikely]]
    log_->shadow.push_back(ray);
  if (!valid_for_embree(ray, 0.0f)) [[unlikely]]
    return true;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRay r;
  r.org_x = ray.o.x;
  r.org_y = ray.o.y;
  r.org_z = ray.o.z;
  r.dir_x = ray.d.x;
  r.dir_y = ray.d.y;
  r.dir_z = ray.d.z;
  r.tnear = 0.0f;
  r.tfar = ray.tmax;
  r.time = 0.0f;
  r.mask = 0xffffffffu;
  r.id = 0;
  r.flags = 0;
  rtcOccluded1(scene_, &ctx, &r);
  return r.tfar < 0.0f;  // Embree sets tfar to -inf on a hit
}

}  // namespace kozu
