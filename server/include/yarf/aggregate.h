// An acceleration structure over triangle meshes, mirroring the Aggregate
// service of geometry.proto (the paper's IAggregate). yarf's default is
// Embree's BVH; a scene or a group that names an Aggregate class has its
// opaque triangle meshes traced by that class instead, placed in Embree's
// BVH as one user geometry, so that it composes with instancing, motion and
// the shapes it does not hold (spheres, cut-outs).
#pragma once

#include <cstdint>
#include <span>

#include "yarf/component.h"
#include "yarf/geometry.h"
#include "yarf/vecmath.h"

namespace yarf {

// A closest hit as an aggregate reports it.
struct AggregateHit {
  // The mesh, by the order of Add, and its triangle.
  uint32_t mesh = kNoShape;
  uint32_t primitive = 0;
  // Distance along the ray.
  float t = kInfinity;
  // Barycentrics of the triangle's second and third corners, as Embree's:
  // the point is (1 - u - v)·p0 + u·p1 + v·p2.
  float u = 0, v = 0;
};

class Aggregate : public virtual Component {
 public:
  static constexpr const char* kInterface = "yarf.v1.Aggregate";

  // Adds a mesh: positions, and three indices into them per triangle. The
  // spans stay valid, unchanged, for the aggregate's life.
  virtual void Add(std::span<const Vec3> positions, std::span<const uint32_t> indices) = 0;
  // Builds the structure once every mesh is added; the queries below come
  // after it, from many threads at once.
  virtual void Commit() = 0;
  // The box around every mesh added.
  // in-process only: Embree asks for it when it places the aggregate in
  // its BVH.
  virtual void Bounds(Vec3& lower, Vec3& upper) const = 0;
  // The closest hit of the ray within [ray.tnear, ray.tfar]; false and
  // `hit` untouched when there is none.
  // in-process only: Embree calls it for each ray inside its traversal;
  // the Intersect service answers for whole scenes.
  virtual bool Intersect(const Ray& ray, AggregateHit& hit) const = 0;
  // Whether any triangle lies on the ray within [ray.tnear, ray.tfar].
  // in-process only: as Intersect.
  virtual bool Occluded(const Ray& ray) const = 0;
};

}  // namespace yarf
