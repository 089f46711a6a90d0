// An Aggregate placed in an Embree scene as one user geometry: Embree's BVH
// reaches it like any other shape and hands it each ray, in the space of
// the instance around it, so a custom aggregate composes with instancing
// and motion.
#pragma once

#include <embree3/rtcore.h>

#include <memory>
#include <vector>

#include "yarf/aggregate.h"

namespace yarf {

class AggregateGeometry {
 public:
  // `shape_ids`: the shape number (geomID) in the Embree scene that each
  // mesh of the aggregate stands for, by the order of Aggregate::Add.
  AggregateGeometry(std::shared_ptr<const Aggregate> aggregate, std::vector<uint32_t> shape_ids)
      : aggregate_(std::move(aggregate)), shape_ids_(std::move(shape_ids)) {}
  AggregateGeometry(const AggregateGeometry&) = delete;
  AggregateGeometry& operator=(const AggregateGeometry&) = delete;

  // Attaches the committed aggregate to `scene` as geometry `id`; this
  // object must outlive the scene's use of it.
  void Attach(RTCDevice device, RTCScene scene, uint32_t id) const;

 private:
  static void Bounds(const RTCBoundsFunctionArguments* args);
  static void Intersect(const RTCIntersectFunctionNArguments* args);
  static void Occluded(const RTCOccludedFunctionNArguments* args);

  std::shared_ptr<const Aggregate> aggregate_;
  std::vector<uint32_t> shape_ids_;
};

}  // namespace yarf
