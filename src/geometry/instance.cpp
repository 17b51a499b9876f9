#include "geometry/instance.h"

#include "geometry/embree_scene.h"

#include <algorithm>
#include <cfloat>
#include <stdexcept>

namespace kozu {

// ---- the object ----------------------------------------------------------------------------------------------

InstancedObject::InstancedObject(std::vector<std::unique_ptr<Shape>> shapes) : shapes_(std::move(shapes)) {
  for (const auto& s : shapes_) s->bounds(lo_, hi_);
}

InstancedObject::~InstancedObject() {
  if (scene_) rtcReleaseScene(scene_);
}

RTCScene InstancedObject::embree_scene(RTCDevice device) const {
  if (scene_ && device_ == device) return scene_;
  if (scene_) rtcReleaseScene(scene_);
  scene_ = rtcNewScene(device);
  device_ = device;
  by_geom_id_.clear();
  if (!scene_) throw std::runtime_error("cannot create an Embree scene for an object");
  rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
  for (const auto& s : shapes_) {
    const unsigned id = attach_shape(device, scene_, *s);
    if (id >= by_geom_id_.size()) by_geom_id_.resize(id + 1, nullptr);
    by_geom_id_[id] = s.get();
  }
  rtcCommitScene(scene_);
  if (rtcGetDeviceError(device) != RTC_ERROR_NONE) throw std::runtime_error("Embree could not build an object");
  return scene_;
}

// ---- the instance --------------------------------------------------------------------------------------------

Instance::Instance(std::shared_ptr<const InstancedObject> object, const Mat4& object_to_world)
    : object_(std::move(object)), rest_(object_to_world) {
  set_transform(object_to_world);
}

void Instance::set_transform(const Mat4& m) {
  to_world_ = m;
  to_object_ = glm::inverse(m);
  normal_to_world_ = glm::transpose(glm::inverse(Mat3(m)));
  norm_ = std::max({glm::length(Vec3(m[0])), glm::length(Vec3(m[1])), glm::length(Vec3(m[2]))});
  det_sign_ = glm::determinant(Mat3(m)) < 0.0f ? -1.0f : 1.0f;
}

unsigned Instance::attach(RTCDevice device, RTCScene scene) const {
  RTCScene object_scene = object_->embree_scene(device);
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
  rtcSetGeometryInstancedScene(geom, object_scene);
  refresh(geom);
  const unsigned id = rtcAttachGeometry(scene, geom);
  rtcReleaseGeometry(geom);
  return id;
}

void Instance::refresh(RTCGeometry geom) const {
  rtcSetGeometryTransform(geom, 0, RTC_FORMAT_FLOAT4X4_COLUMN_MAJOR, &to_world_[0][0]);
  rtcCommitGeometry(geom);
}

void Instance::set_pose(const Mat4& pose) { set_transform(pose * rest_); }

void Instance::bounds(Vec3& lo, Vec3& hi) const {
  Vec3 olo(kInfinity), ohi(-kInfinity);
  object_->bounds(olo, ohi);
  if (!(olo.x <= ohi.x)) return;
  for (int c = 0; c < 8; ++c) {
    const Vec3 p(c & 1 ? ohi.x : olo.x, c & 2 ? ohi.y : olo.y, c & 4 ? ohi.z : olo.z);
    const Vec3 w = Vec3(to_world_ * Vec4(p, 1.0f));
    lo = glm::min(lo, w);
    hi = glm::max(hi, w);
  }
}

void Instance::interaction(const Ray&, float t, uint32_t prim, float, float, const Vec3&,
                           SurfaceInteraction& si) const {
  si = SurfaceInteraction{};
  si.t = t;
  si.prim = prim;
}

void Instance::instanced_interaction(const Ray& ray, float t, unsigned geom_id, uint32_t prim, float u, float v,
                                     const Vec3& ng, SurfaceInteraction& si) const {
  const Shape* shape = object_->shape(geom_id);
  // Embree intersects the object with the ray transformed by M^-1, direction unnormalised: the same t.
  const Ray local{Vec3(to_object_ * Vec4(ray.o, 1.0f)), Mat3(to_object_) * ray.d, ray.tmax};
  si.p_error = 0.0f;
  shape->interaction(local, t, prim, u, v, ng, si);
  const Vec3 p_object = si.p;
  si.p = Vec3(to_world_ * Vec4(p_object, 1.0f));
  // The object's bound grows with M; the product M p + t rounds by a few ulps of its terms' magnitudes.
  const Vec3 translation(to_world_[3]);
  si.p_error =
      si.p_error * norm_ +
      8.0f * FLT_EPSILON * (3.0f * norm_ * max_component(glm::abs(p_object)) + max_component(glm::abs(translation)));
  si.ng = glm::normalize(normal_to_world_ * si.ng);
  si.shading = Frame(glm::normalize(normal_to_world_ * si.shading.n));
  si.wo = -ray.d;
  si.front_face = glm::dot(si.wo, si.ng) > 0.0f;
  si.t = t;
  si.instance = this;
}

SurfaceInteraction Instance::to_object_space(const SurfaceInteraction& si) const {
  SurfaceInteraction o = si;
  const Mat3 normal_to_object = glm::transpose(Mat3(to_world_));  // (M^-1)^-T
  o.p = Vec3(to_object_ * Vec4(si.p, 1.0f));
  o.ng = glm::normalize(normal_to_object * si.ng);
  o.shading = Frame(glm::normalize(normal_to_object * si.shading.n));
  o.wo = glm::normalize(Mat3(to_object_) * si.wo);
  o.instance = nullptr;
  return o;
}

void Instance::uv_derivatives_of(const SurfaceInteraction& si, Vec3* dpdu, Vec3* dpdv) const {
  si.shape->uv_derivatives(to_object_space(si), dpdu, dpdv);
  *dpdu = Mat3(to_world_) * *dpdu;
  *dpdv = Mat3(to_world_) * *dpdv;
}

Vec4 Instance::tangent_of(const SurfaceInteraction& si) const {
  const Vec4 t = si.shape->tangent(to_object_space(si));
  Vec3 w = Mat3(to_world_) * Vec3(t);
  // Back perpendicular to the world shading normal (M does not keep angles unless it is a similarity).
  w -= glm::dot(w, si.shading.n) * si.shading.n;
  const float l = glm::length(w);
  if (!(l > 1e-12f)) return Vec4(0.0f);
  // A mirror turns the bitangent's handedness.
  return Vec4(w / l, t.w * det_sign_);
}

float Instance::curvature_of(const SurfaceInteraction& si) const {
  // Exact for rotations and uniform scales; under a non-uniform scale, the mean scale (its cube root).
  const float scale = std::cbrt(std::abs(glm::determinant(Mat3(to_world_))));
  return si.shape->curvature(to_object_space(si)) / scale;
}

// ---- readers of a hit ----------------------------------------------------------------------------------------

void surface_uv_derivatives(const SurfaceInteraction& si, Vec3* dpdu, Vec3* dpdv) {
  if (si.instance)
    si.instance->uv_derivatives_of(si, dpdu, dpdv);
  else
    si.shape->uv_derivatives(si, dpdu, dpdv);
}

Vec4 surface_tangent(const SurfaceInteraction& si) {
  return si.instance ? si.instance->tangent_of(si) : si.shape->tangent(si);
}

float surface_curvature(const SurfaceInteraction& si) {
  return si.instance ? si.instance->curvature_of(si) : si.shape->curvature(si);
}

}  // namespace kozu
