// Points on light surfaces seen from many reference points at once, eight
// at a time in 256-bit vectors (AVX2 and FMA, with xsimd's trigonometry):
// the batched forms of SphereSurface's cone sampling and of
// SampleSphericalTriangle, for CPUs that have those instructions
// (LightPointKernelsAvailable). Each lane computes what the scalar code
// does, to rounding; light_point_kernels_test.cc holds them to it.
#pragma once

#include <array>
#include <cstdint>
#include <span>

#include "yarf/shape.h"
#include "yarf/vecmath.h"

namespace yarf {

struct SphereGeometry;

// Whether this CPU runs the kernels below.
bool LightPointKernelsAvailable();

// For each point from[k], the point of `sphere` in the direction drawn
// uniformly in the cone the sphere subtends from it (uniform[3k + 1],
// uniform[3k + 2]; uniform[3k] is not read), with its normal, uv and pdf
// per unit solid angle: what SphereSurface samples by cone. Meaningless
// for points inside the sphere.
void SampleSphereCones(const SphereGeometry& sphere, std::span<const Vec3> from, std::span<const float> uniform,
                       std::span<SurfaceSample> out);

// A triangle as seen from a reference point and a direction drawn
// uniformly in its solid angle: the barycentrics (b1, b2) of the point it
// meets, b0 = 1 - b1 - b2.
struct SphericalTriangleSample {
  float b1 = 0, b2 = 0;
  // The solid angle; 0 from a corner.
  float solid_angle = 0;
  // False where SampleSphericalTriangle fails (seen edge-on, from a corner).
  bool sampled = false;
};

// For each point from[k], triangle corners[triangle[k]] seen from it and
// sampled uniformly in solid angle with uniform[3k + 1], uniform[3k + 2],
// as SphericalTriangle::Seen and SampleSphericalTriangle do one by one.
void SampleSphericalTriangles(std::span<const std::array<Vec3, 3>> corners, std::span<const uint32_t> triangle,
                              std::span<const Vec3> from, std::span<const float> uniform,
                              std::span<SphericalTriangleSample> out);

}  // namespace yarf
