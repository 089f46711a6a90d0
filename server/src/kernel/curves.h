// Curves (hair, fur, grass) as Embree intersects them: segments of cubic
// Bézier or B-spline polynomials, or straight ones, swept by a radius that
// varies along them, either as tubes or as ribbons turned to face the ray.
#pragma once

#include <embree3/rtcore.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "yarf/math.h"

namespace yarf {

struct CurveGeometry {
  enum class Basis { kBezier, kBSpline, kLinear };
  Basis basis = Basis::kBezier;
  // A ribbon facing each ray rather than a tube.
  bool flat = false;
  // x, y, z and the radius there.
  std::vector<std::array<float, 4>> points;
  // Each segment's first control point.
  std::vector<uint32_t> segments;

  // Control points a segment spans: 4 for the cubics, 2 for straight ones.
  uint32_t PointsPerSegment() const { return basis == Basis::kLinear ? 2 : 4; }
  // The direction of the centre line at `u` in [0, 1] along `segment`,
  // ∂p/∂u (not unit; zero where the control points coincide).
  Vec3 Tangent(uint32_t segment, float u) const;
  // The reason these curves cannot be traced (segments beyond the points,
  // a coordinate or radius that is not finite, a negative radius), empty
  // when they can.
  std::string Defect() const;
};

// The curves as Embree geometry `id` of `scene`.
void AttachCurves(RTCDevice device, RTCScene scene, uint32_t id, const CurveGeometry& curves);

}  // namespace yarf
