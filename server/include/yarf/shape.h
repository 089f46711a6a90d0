// A shape's measures and the two ways to sample points on it, mirroring the
// Shape, SampleSurfaceArea and SampleSurfaceDirection services of
// geometry.proto (the paper's IShape, ISampleSurfaceArea and
// ISampleSurfaceDirection). World space, scene units.
#pragma once

#include <cstdint>
#include <span>

#include "yarf/vecmath.h"

namespace yarf {

// A point of a shape's surface, as its samplers give it and as their
// densities are asked for.
struct SurfaceSample {
  Vec3 position;
  // Unit, on the side the shape's normals face (flipped ones included).
  Vec3 normal;
  // The primitive (triangle) the point lies on, and its texture
  // coordinates there.
  uint32_t primitive = 0;
  float u = 0, v = 0;
  // Per unit area (SampleSurfaceArea), or per unit solid angle at the
  // reference point (SampleSurfaceDirection); 0 when nothing was sampled.
  float pdf = 0;
};

class Shape {
 public:
  static constexpr const char* kInterface = "yarf.v1.Shape";

  virtual ~Shape() = default;
  // Axis-aligned box around the shape.
  virtual void Bounds(Vec3& lower, Vec3& upper) const = 0;
  // Surface area, squared scene units.
  virtual float Area() const = 0;
};

// Points uniform in area: the density is 1/Area() everywhere.
class SurfaceAreaSampler {
 public:
  static constexpr const char* kInterface = "yarf.v1.SampleSurfaceArea";

  virtual ~SurfaceAreaSampler() = default;
  // uniform: [N,3], the primitive's choice (in proportion to its area)
  // and then the point on it. A mesh picks its triangle with the point's
  // first number instead, rescaled within the triangle's share, so that
  // pairs stratified over the square stay stratified over the whole mesh
  // (the choice's number is then unused).
  virtual void Sample(std::span<const float> uniform, std::span<SurfaceSample> out) const = 0;
};

// Points seen from reference points, with densities per solid angle there:
// a sphere by the cone it subtends, a triangle that subtends a fair solid
// angle by that solid angle, anything else by area converted.
class SurfaceDirectionSampler {
 public:
  static constexpr const char* kInterface = "yarf.v1.SampleSurfaceDirection";

  virtual ~SurfaceDirectionSampler() = default;
  // uniform: [N,3] as SurfaceAreaSampler's; from: [N] reference points.
  virtual void Sample(std::span<const Vec3> from, std::span<const float> uniform,
                      std::span<SurfaceSample> out) const = 0;
  // The density Sample has, per solid angle at from[k], for the point
  // at[k] of the surface (its position and primitive; the normal is the
  // surface's own) that the ray from from[k] toward it meets first.
  virtual void Pdf(std::span<const Vec3> from, std::span<const SurfaceSample> at,
                   std::span<float> pdf) const = 0;
};

}  // namespace yarf
