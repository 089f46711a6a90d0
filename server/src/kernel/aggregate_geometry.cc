#include "kernel/aggregate_geometry.h"

#include "yarf/error.h"

namespace yarf {
namespace {

Ray RayOf(RTCRayN* rays, unsigned n, unsigned i) {
  Ray ray;
  ray.origin = Vec3(RTCRayN_org_x(rays, n, i), RTCRayN_org_y(rays, n, i), RTCRayN_org_z(rays, n, i));
  ray.direction = Vec3(RTCRayN_dir_x(rays, n, i), RTCRayN_dir_y(rays, n, i), RTCRayN_dir_z(rays, n, i));
  ray.tnear = RTCRayN_tnear(rays, n, i);
  ray.tfar = RTCRayN_tfar(rays, n, i);
  ray.time = RTCRayN_time(rays, n, i);
  return ray;
}

}  // namespace

void AggregateGeometry::Attach(RTCDevice device, RTCScene scene, uint32_t id) const {
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
  if (!geom) throw Error("Embree could not make the aggregate's geometry");
  // One primitive: the whole aggregate, found by its box.
  rtcSetGeometryUserPrimitiveCount(geom, 1);
  rtcSetGeometryUserData(geom, const_cast<AggregateGeometry*>(this));
  rtcSetGeometryBoundsFunction(geom, &AggregateGeometry::Bounds, nullptr);
  rtcSetGeometryIntersectFunction(geom, &AggregateGeometry::Intersect);
  rtcSetGeometryOccludedFunction(geom, &AggregateGeometry::Occluded);
  rtcCommitGeometry(geom);
  rtcAttachGeometryByID(scene, geom, id);
  rtcReleaseGeometry(geom);
}

void AggregateGeometry::Bounds(const RTCBoundsFunctionArguments* args) {
  const auto* self = static_cast<const AggregateGeometry*>(args->geometryUserPtr);
  Vec3 lower, upper;
  self->aggregate_->Bounds(lower, upper);
  *args->bounds_o = {lower.x, lower.y, lower.z, 0, upper.x, upper.y, upper.z, 0};
}

void AggregateGeometry::Intersect(const RTCIntersectFunctionNArguments* args) {
  const auto* self = static_cast<const AggregateGeometry*>(args->geometryUserPtr);
  RTCRayN* rays = RTCRayHitN_RayN(args->rayhit, args->N);
  RTCHitN* hits = RTCRayHitN_HitN(args->rayhit, args->N);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    const Ray ray = RayOf(rays, args->N, i);
    AggregateHit hit;
    if (!self->aggregate_->Intersect(ray, hit)) continue;
    // A hit outside the ray or of no mesh added is no hit.
    if (!(hit.t >= ray.tnear && hit.t <= ray.tfar) || hit.mesh >= self->shape_ids_.size()) continue;
    // The aggregate's answer stands in for the shape's own geometry: the
    // scene reads the shape from geomID as for a triangle mesh of its own.
    RTCRayN_tfar(rays, args->N, i) = hit.t;
    RTCHitN_Ng_x(hits, args->N, i) = 0;
    RTCHitN_Ng_y(hits, args->N, i) = 0;
    RTCHitN_Ng_z(hits, args->N, i) = 0;
    RTCHitN_u(hits, args->N, i) = hit.u;
    RTCHitN_v(hits, args->N, i) = hit.v;
    RTCHitN_primID(hits, args->N, i) = hit.primitive;
    RTCHitN_geomID(hits, args->N, i) = self->shape_ids_[hit.mesh];
    for (unsigned level = 0; level < RTC_MAX_INSTANCE_LEVEL_COUNT; ++level)
      RTCHitN_instID(hits, args->N, i, level) = args->context->instID[level];
  }
}

void AggregateGeometry::Occluded(const RTCOccludedFunctionNArguments* args) {
  const auto* self = static_cast<const AggregateGeometry*>(args->geometryUserPtr);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    if (self->aggregate_->Occluded(RayOf(args->ray, args->N, i)))
      RTCRayN_tfar(args->ray, args->N, i) = -kInfinity;
  }
}

}  // namespace yarf
