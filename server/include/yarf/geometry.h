// Ray queries, mirroring the Intersect service of geometry.proto. In
// process a batch is an array of Ray records; on the wire the same fields
// travel as the dense arrays of RayBatch.
#pragma once

#include <cstdint>
#include <algorithm>
#include <cmath>
#include <limits>
#include <span>

#include "yarf/vecmath.h"

namespace yarf {

inline constexpr uint32_t kNoShape = 0xFFFFFFFFu;
inline constexpr float kInfinity = std::numeric_limits<float>::infinity();

struct Ray {
  Vec3 origin;
  float tnear = 0;
  Vec3 direction;
  float tfar = kInfinity;
  // When in the shutter interval, in [0, 1]: where moving shapes are.
  float time = 0;
};

struct Hit {
  float t = kInfinity;
  // Index of the shape placement hit (kNoShape for a miss) and its primitive.
  uint32_t shape = kNoShape;
  uint32_t primitive = 0;
  // Texture coordinates: a mesh's uvs interpolated (its barycentrics b1,
  // b2 when it has none), a sphere's (φ/2π, θ/π) in its own frame.
  float u = 0, v = 0;
  // Barycentric coordinates of the triangle's second and third corners
  // (0 for spheres).
  float b1 = 0, b2 = 0;
  // Unit geometric normal, world space, on the shape's outward side (a
  // mesh with vertex normals: the side they point to).
  Vec3 normal;
  // Unit shading normal: the vertex normals interpolated, on `normal`'s
  // side; `normal` itself where there are none.
  Vec3 shading_normal;
  // ∂p/∂u and ∂p/∂v, world space (not unit); for a mesh without uvs, of
  // its barycentric parameterisation, and zero when it has no vertex
  // normals either (nothing to orient a frame by).
  Vec3 dpdu, dpdv;
  // Whether uv is a parameterisation of the surface's own (a mesh's uvs,
  // an analytic shape's), not barycentrics: what texture footprints and
  // bump maps need.
  bool parameterised = false;

  bool Found() const { return shape != kNoShape; }
};

class Intersector {
 public:
  static constexpr const char* kInterface = "yarf.v1.Intersect";

  virtual ~Intersector() = default;
  // Closest hit of each ray, every field of every hit written (a miss is
  // Hit{}). The server answers CrossSection (every hit along each ray) by
  // intersecting again from just past each hit.
  // rpc: Intersect, CrossSection
  virtual void Intersect(std::span<const Ray> rays, std::span<Hit> hits) const = 0;
  // occluded[i] = 1 when something lies on ray i within its interval.
  virtual void Occluded(std::span<const Ray> rays, std::span<uint8_t> occluded) const = 0;
};

// How far a ray starts or stops short of a surface point so that float
// rounding does not make it hit that surface: relative to the coordinates.
inline float SurfaceOffset(Vec3 p) {
  return 1e-4f * std::max(1.0f, std::max(std::abs(p.x), std::max(std::abs(p.y), std::abs(p.z))));
}

// The origin of a ray leaving a surface at p with geometric normal n
// toward direction d, moved off the surface to the side d goes to.
inline Vec3 OffsetRayOrigin(Vec3 p, Vec3 n, Vec3 d) {
  const float offset = SurfaceOffset(p);
  return p + n * (Dot(n, d) > 0 ? offset : -offset);
}

// The shadow ray from surface point p (normal n) to the point `to`: it
// leaves p's surface and stops `margin` short of `to`, whatever the
// offsets do to its length. Made in one expression, so that a caller
// copying it does not reread fields just stored one by one (a stall).
inline Ray ShadowRay(Vec3 p, Vec3 n, Vec3 to, float margin, float time = 0) {
  const Vec3 origin = OffsetRayOrigin(p, n, to - p);
  const Vec3 d = to - origin;
  const float length = Length(d);
  return {origin, 0, length > 0 ? d / length : n, std::max(0.0f, length - margin), time};
}
// The same stopping short of `to`'s surface.
inline Ray ShadowRay(Vec3 p, Vec3 n, Vec3 to) { return ShadowRay(p, n, to, SurfaceOffset(to)); }

}  // namespace yarf
