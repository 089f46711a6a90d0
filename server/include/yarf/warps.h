// Sampling warps: maps from uniform numbers in [0,1)^2 to points of the
// disk, the sphere and its parts, and triangles, each with the density it
// produces (Shirley, "Nonuniform random point sets via warping", 1992).
// Each warp is a pair SampleX / XPdf; a pdf returns 0 outside the warp's
// domain so that callers and tests can evaluate it anywhere. Directions
// are unit vectors in a local frame whose +z is the axis (the normal).
// Also here: the scattering helpers BSDFs share (mirror reflection,
// refraction, the Fresnel factor of a smooth dielectric).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>

#include "yarf/vecmath.h"

namespace yarf {

// The unit vector at polar angle θ (given by sin θ, cos θ) and azimuth φ.
inline Vec3 SphericalDirection(float sin_theta, float cos_theta, float phi) {
  return {sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta};
}

// sin θ from cos θ, robust to |cos θ| rounding slightly above 1.
inline float SinFromCos(float cos_theta) {
  return std::sqrt(std::max(0.0f, 1.0f - cos_theta * cos_theta));
}

// Concentric map of the square onto the unit disk (Shirley & Chiu 1997):
// it maps concentric squares to concentric circles, so strata of the
// square stay compact on the disk, unlike the polar map's slivers.
inline std::array<float, 2> SampleConcentricDisk(float u0, float u1) {
  const float a = 2.0f * u0 - 1.0f;
  const float b = 2.0f * u1 - 1.0f;
  if (a == 0 && b == 0) return {0.0f, 0.0f};
  float r, phi;
  if (std::abs(a) > std::abs(b)) {
    r = a;
    phi = (kPi / 4) * (b / a);
  } else {
    r = b;
    phi = kPi / 2 - (kPi / 4) * (a / b);
  }
  return {r * std::cos(phi), r * std::sin(phi)};
}

// Area density: uniform over the unit disk.
inline float ConcentricDiskPdf(float x, float y) {
  return x * x + y * y <= 1.0f ? kInvPi : 0.0f;
}

// Cosine-weighted hemisphere (Malley's method): points uniform on the
// disk, lifted onto the hemisphere, have density cos θ / π.
inline Vec3 SampleCosineHemisphere(float u0, float u1) {
  const auto [x, y] = SampleConcentricDisk(u0, u1);
  return {x, y, std::sqrt(std::max(0.0f, 1.0f - x * x - y * y))};
}

inline float CosineHemispherePdf(float cos_theta) {
  return cos_theta > 0 ? cos_theta * kInvPi : 0.0f;
}

// Uniform over the hemisphere z ≥ 0: cos θ is uniform in [0, 1]
// (Archimedes' hat-box theorem).
inline Vec3 SampleUniformHemisphere(float u0, float u1) {
  const float cos_theta = u0;
  return SphericalDirection(SinFromCos(cos_theta), cos_theta, 2 * kPi * u1);
}

inline float UniformHemispherePdf(float cos_theta) {
  return cos_theta >= 0 ? 1.0f / (2 * kPi) : 0.0f;
}

// Uniform over the sphere: cos θ is uniform in [-1, 1].
inline Vec3 SampleUniformSphere(float u0, float u1) {
  const float cos_theta = 1.0f - 2.0f * u0;
  return SphericalDirection(SinFromCos(cos_theta), cos_theta, 2 * kPi * u1);
}

inline float UniformSpherePdf() { return 1.0f / (4 * kPi); }

// Uniform over the cone of directions within angle θmax of +z, given
// cos θmax < 1: cos θ is uniform in [cos θmax, 1]. Written as 1 - u·(1 -
// cos θmax) so that the result never rounds below cos θmax.
inline Vec3 SampleUniformCone(float u0, float u1, float cos_theta_max) {
  const float cos_theta = 1.0f - u0 * (1.0f - cos_theta_max);
  return SphericalDirection(SinFromCos(cos_theta), cos_theta, 2 * kPi * u1);
}

inline float UniformConePdf(float cos_theta, float cos_theta_max) {
  return cos_theta >= cos_theta_max ? 1.0f / (2 * kPi * (1.0f - cos_theta_max)) : 0.0f;
}

// Uniform over a triangle, as barycentrics (b0, b1, b2) of its vertices
// (p = b0·p0 + b1·p1 + b2·p2). Heitz's low-distortion map (2019) folds
// the square onto the triangle without the square root's stretching.
inline std::array<float, 3> SampleUniformTriangle(float u0, float u1) {
  float b0, b1;
  if (u0 < u1) {
    b0 = u0 / 2;
    b1 = u1 - b0;
  } else {
    b1 = u1 / 2;
    b0 = u0 - b1;
  }
  return {b0, b1, 1.0f - b0 - b1};
}

// Area density on a triangle of the given area.
inline float UniformTrianglePdf(float area) { return 1.0f / area; }

// The Phong lobe: density ∝ cos^n θ around +z; cos θ = u^(1/(n+1)) inverts
// its marginal CDF in cos θ.
inline Vec3 SamplePhongLobe(float u0, float u1, float exponent) {
  const float cos_theta = std::pow(u0, 1.0f / (exponent + 1.0f));
  return SphericalDirection(SinFromCos(cos_theta), cos_theta, 2 * kPi * u1);
}

inline float PhongLobePdf(float cos_theta, float exponent) {
  return cos_theta > 0 ? (exponent + 1.0f) / (2 * kPi) * std::pow(cos_theta, exponent) : 0.0f;
}

// Mirror direction of w about the normal +z.
inline Vec3 Reflect(Vec3 w) { return {-w.x, -w.y, w.z}; }

// The direction in which light arriving along -wi continues through a
// smooth interface with relative index eta = n(below) / n(above) (+z is
// "above"; wi.z < 0 means wi lies below). The result points to the other
// side of the surface. Returns false on total internal reflection.
inline bool Refract(Vec3 wi, float eta, Vec3* wt) {
  const float cos_i = wi.z;
  // Relative index of the far side over the near side.
  const float eta_rel = cos_i >= 0 ? eta : 1.0f / eta;
  const float sin2_t = std::max(0.0f, 1.0f - cos_i * cos_i) / (eta_rel * eta_rel);
  if (sin2_t >= 1.0f) return false;
  const float cos_t = std::sqrt(1.0f - sin2_t);
  // Tangential components shrink by 1/eta_rel (Snell); the normal one
  // flips side.
  *wt = {-wi.x / eta_rel, -wi.y / eta_rel, cos_i >= 0 ? -cos_t : cos_t};
  return true;
}

// Fresnel reflectance of unpolarised light at a smooth dielectric
// interface: the mean of the s- and p-polarised reflectances. cos_i is the
// cosine of the incident direction with +z, negative when it lies below;
// eta = n(below) / n(above). Returns 1 on total internal reflection.
inline float FresnelDielectric(float cos_i, float eta) {
  cos_i = std::clamp(cos_i, -1.0f, 1.0f);
  if (cos_i < 0) {
    eta = 1.0f / eta;
    cos_i = -cos_i;
  }
  const float sin2_t = (1.0f - cos_i * cos_i) / (eta * eta);
  if (sin2_t >= 1.0f) return 1.0f;
  const float cos_t = std::sqrt(1.0f - sin2_t);
  const float r_parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
  const float r_perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  return 0.5f * (r_parallel * r_parallel + r_perpendicular * r_perpendicular);
}

}  // namespace yarf
