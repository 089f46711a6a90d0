#include "kernel/curves.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "yarf/error.h"

namespace yarf {
namespace {

Vec3 At(const std::array<float, 4>& p) { return Vec3(p[0], p[1], p[2]); }

RTCGeometryType EmbreeType(const CurveGeometry& curves) {
  using Basis = CurveGeometry::Basis;
  switch (curves.basis) {
    case Basis::kBezier:
      return curves.flat ? RTC_GEOMETRY_TYPE_FLAT_BEZIER_CURVE : RTC_GEOMETRY_TYPE_ROUND_BEZIER_CURVE;
    case Basis::kBSpline:
      return curves.flat ? RTC_GEOMETRY_TYPE_FLAT_BSPLINE_CURVE : RTC_GEOMETRY_TYPE_ROUND_BSPLINE_CURVE;
    case Basis::kLinear:
      return curves.flat ? RTC_GEOMETRY_TYPE_FLAT_LINEAR_CURVE : RTC_GEOMETRY_TYPE_ROUND_LINEAR_CURVE;
  }
  throw Error("curves: unknown basis");
}

// A tube is a fibre: the light that enters it is the business of its
// material (hair's lobes carry it through), and a ray that starts on its
// surface toward the inside, or enters at an end, leaves from the far
// side. So a tube's inner wall is never met: hits where the ray runs
// along the outward normal are passed over, as Mitsuba 3's tubes do.
void SkipInnerWall(const RTCFilterFunctionNArguments* args) {
  const unsigned n = args->N;
  for (unsigned i = 0; i < n; ++i) {
    if (args->valid[i] != -1) continue;
    const float along = RTCRayN_dir_x(args->ray, n, i) * RTCHitN_Ng_x(args->hit, n, i) +
                        RTCRayN_dir_y(args->ray, n, i) * RTCHitN_Ng_y(args->hit, n, i) +
                        RTCRayN_dir_z(args->ray, n, i) * RTCHitN_Ng_z(args->hit, n, i);
    if (along > 0) args->valid[i] = 0;
  }
}

}  // namespace

Vec3 CurveGeometry::Tangent(uint32_t segment, float u) const {
  const uint32_t first = segments[segment];
  if (basis == Basis::kLinear) return At(points[first + 1]) - At(points[first]);
  const Vec3 p0 = At(points[first]), p1 = At(points[first + 1]), p2 = At(points[first + 2]),
             p3 = At(points[first + 3]);
  const float v = 1 - u;
  if (basis == Basis::kBezier) return ((p1 - p0) * (v * v) + (p2 - p1) * (2 * v * u) + (p3 - p2) * (u * u)) * 3.0f;
  // The derivatives of the uniform cubic B-spline's four basis functions.
  return p0 * (-0.5f * v * v) + p1 * (0.5f * (3 * u * u - 4 * u)) + p2 * (0.5f * (-3 * u * u + 2 * u + 1)) +
         p3 * (0.5f * u * u);
}

std::string CurveGeometry::Defect() const {
  if (segments.empty()) return "curves need at least one segment";
  for (const auto& p : points) {
    for (const float c : p)
      if (!std::isfinite(c) || std::abs(c) > 1e18f) return "a control point is not a finite number";
    if (p[3] < 0) return "a control point's radius is negative";
  }
  for (const uint32_t first : segments)
    if (uint64_t(first) + PointsPerSegment() > points.size())
      return "segment from control point " + std::to_string(first) + " needs " +
             std::to_string(PointsPerSegment()) + " control points, and there are " + std::to_string(points.size());
  return {};
}

void AttachCurves(RTCDevice device, RTCScene scene, uint32_t id, const CurveGeometry& curves) {
  RTCGeometry geom = rtcNewGeometry(device, EmbreeType(curves));
  auto* points = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4,
                                                             4 * sizeof(float), curves.points.size()));
  for (size_t k = 0; k < curves.points.size(); ++k)
    for (int c = 0; c < 4; ++c) points[4 * k + c] = curves.points[k][c];
  auto* segments = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT,
                                                                  sizeof(uint32_t), curves.segments.size()));
  std::copy(curves.segments.begin(), curves.segments.end(), segments);
  if (!curves.flat) {
    rtcSetGeometryIntersectFilterFunction(geom, &SkipInnerWall);
    rtcSetGeometryOccludedFilterFunction(geom, &SkipInnerWall);
  }
  rtcCommitGeometry(geom);
  rtcAttachGeometryByID(scene, geom, id);
  rtcReleaseGeometry(geom);
}

}  // namespace yarf
