// The surfaces of a scene's shapes, in world space, as Shape and sampler
// components: what the kernel's light sampling draws points from and what
// yarfd's geometry services serve for a running job's shapes.
#pragma once

#include <array>
#include <vector>

#include "kernel/mesh_io.h"
#include "yarf/geometry.h"
#include "yarf/shape.h"
#include "yarf/support/warps.h"

namespace yarf {

// A sphere's texture coordinates (Mitsuba's: u = φ/2π from its own x
// axis, v = θ/π from its z axis) and ∂p/∂u, ∂p/∂v, at unit direction d
// from its centre, for radius r; `axes` are its x, y, z in world space.
void SphereParameters(const std::array<Vec3, 3>& axes, Vec3 d, float r, Hit& hit);

class ShapeSurface : public Shape, public SurfaceAreaSampler, public SurfaceDirectionSampler {
 public:
  // Both samplers' Sample, told apart by their arguments.
  using SurfaceAreaSampler::Sample;
  using SurfaceDirectionSampler::Sample;

  // The surface gathered into one point as seen from `seen_from`, for
  // methods that want hard shadows, and the area that point stands for: a
  // mesh's area-weighted centroid and mean normal with its whole area, a
  // sphere's point facing the viewer with its cross-section.
  virtual SurfaceSample Gathered(Vec3 seen_from, float& area) const = 0;
  // The cone around `axis` holding every normal of the surface, as the
  // cosine of its half-angle; false when the normals face every way.
  virtual bool NormalCone(Vec3& axis, float& cos_theta) const = 0;
  // A point uniform in area (pdf 1/Area) from two uniform numbers, for
  // callers that have only two (a camera ray's film position): u0 picks the
  // primitive in proportion to area, and its remainder within that
  // primitive's share, uniform on [0,1) and independent of the choice, is
  // the point's first coordinate there, u1 its second.
  virtual SurfaceSample SamplePoint(float u0, float u1) const = 0;
};

struct SphereGeometry {
  Vec3 center;
  float radius = 1;
  std::array<Vec3, 3> axes{Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  bool flip_normals = false;
};

// The point of `sphere` at unit direction d from its centre, with its
// normal and uv (no pdf).
SurfaceSample SpherePointAt(const SphereGeometry& sphere, Vec3 d);
// The point of `sphere` in the direction from p drawn uniformly in the
// cone the sphere subtends (u0, u1), and that density per unit solid
// angle; p must lie outside the sphere.
SurfaceSample SampleSphereCone(const SphereGeometry& sphere, Vec3 p, float u0, float u1);

class SphereSurface final : public ShapeSurface {
 public:
  // by_cone: points outside the sphere find it by the cone it subtends
  // (uniform in that solid angle); otherwise, and from inside, by area.
  SphereSurface(const SphereGeometry& sphere, bool by_cone) : sphere_(sphere), by_cone_(by_cone) {}

  void Bounds(Vec3& lower, Vec3& upper) const override;
  float Area() const override;
  void Sample(std::span<const float> uniform, std::span<SurfaceSample> out) const override;
  void Sample(std::span<const Vec3> from, std::span<const float> uniform,
              std::span<SurfaceSample> out) const override;
  void Pdf(std::span<const Vec3> from, std::span<const SurfaceSample> at, std::span<float> pdf) const override;
  SurfaceSample Gathered(Vec3 seen_from, float& area) const override;
  bool NormalCone(Vec3& axis, float& cos_theta) const override { return false; }
  SurfaceSample SamplePoint(float u0, float u1) const override;

 private:
  // SpherePointAt of this sphere.
  SurfaceSample At(Vec3 d) const;
  bool SeenByCone(Vec3 p) const;

  SphereGeometry sphere_;
  bool by_cone_;
};

class MeshSurface final : public ShapeSurface {
 public:
  // `corners`: each triangle's corners in world space; `normals`: their
  // unit normals, flipped as the shape's are; `mesh` (which must outlive
  // this) gives texture coordinates. by_solid_angle: a triangle that
  // subtends a fair solid angle from the reference point is sampled
  // uniformly in it (pbrt-v4); otherwise every triangle by area (Mitsuba).
  MeshSurface(std::vector<std::array<Vec3, 3>> corners, std::vector<Vec3> normals, const TriangleMesh& mesh,
              bool by_solid_angle);

  void Bounds(Vec3& lower, Vec3& upper) const override;
  float Area() const override { return area_; }
  void Sample(std::span<const float> uniform, std::span<SurfaceSample> out) const override;
  void Sample(std::span<const Vec3> from, std::span<const float> uniform,
              std::span<SurfaceSample> out) const override;
  void Pdf(std::span<const Vec3> from, std::span<const SurfaceSample> at, std::span<float> pdf) const override;
  SurfaceSample Gathered(Vec3 seen_from, float& area) const override;
  bool NormalCone(Vec3& axis, float& cos_theta) const override;
  SurfaceSample SamplePoint(float u0, float u1) const override;

 private:
  // The triangle u picks in proportion to area, and its share of the
  // area; u becomes its place within the triangle's share, uniform on
  // [0,1) again, so that a pair of numbers stratified over the square
  // stays stratified over the whole mesh (as Mitsuba's meshes do).
  uint32_t Pick(float& u, float& share) const;
  float Share(uint32_t triangle) const;
  // Whether a triangle that subtends `solid_angle` is sampled by it.
  static bool SampledBySolidAngle(float solid_angle);
  // Whether triangle t is sampled by its solid angle from p, and the
  // triangle as seen from p.
  bool BySolidAngle(uint32_t t, Vec3 p, SphericalTriangle& seen) const;
  // Sample(from, ...) by solid angle, eight points at a time
  // (light_point_kernels.h); those the kernel leaves by area.
  void SampleBatched(std::span<const Vec3> from, std::span<const float> uniform,
                     std::span<SurfaceSample> out) const;
  // A point of triangle t uniform in its area, with the density per solid
  // angle at p that Sample gives it.
  void SampleByArea(uint32_t t, Vec3 p, float u0, float u1, SurfaceSample& out) const;
  // Sets all but the density of `out` to the point of triangle t at
  // barycentrics b, with its uv. In place, field by field: a sample built
  // apart and copied in was reloaded whole before its fields had been
  // stored, a stall on every sample.
  void At(uint32_t t, const std::array<float, 3>& b, SurfaceSample& out) const;

  std::vector<std::array<Vec3, 3>> corners_;
  std::vector<Vec3> normals_;
  // Running sum of the triangles' areas.
  std::vector<float> cdf_;
  float area_ = 0;
  // Area-weighted: the centroid, and the normals' mean (not unit).
  Vec3 centroid_, normal_sum_;
  const TriangleMesh* mesh_;
  bool by_solid_angle_;
};

}  // namespace yarf
