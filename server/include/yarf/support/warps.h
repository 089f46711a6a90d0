// Sampling warps: maps from uniform numbers in [0,1)^2 to points of the
// disk, the sphere and its parts, and triangles, each with the density it
// produces (Shirley, "Nonuniform random point sets via warping", 1992).
// Each warp is a pair SampleX / XPdf, plus InvertX where the map is a
// bijection; a pdf returns 0 outside the warp's image so that callers and
// tests can evaluate it anywhere. Directions are unit vectors in a local
// frame whose +z is the axis (the normal).
// Also here: the scattering helpers BSDFs share (mirror reflection,
// refraction, the Fresnel factor of a smooth dielectric).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

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

// Whether w is a unit vector up to the rounding of a float computation:
// the image of every direction warp, off which its pdf is 0.
inline bool OnUnitSphere(Vec3 w) { return std::abs(Dot(w, w) - 1.0f) <= 1e-3f; }

// 1 - cos θ of a unit vector. Near the pole 1 - w.z cancels to nothing,
// while sin²θ / (1 + cos θ) keeps the precision of w.x and w.y.
inline float OneMinusCosTheta(Vec3 w) {
  return w.z > 0 ? (w.x * w.x + w.y * w.y) / (1.0f + w.z) : 1.0f - w.z;
}

// A preimage coordinate clamped into [0, 1), the domain of every warp:
// rounding (or a point off the image) must not leave it.
inline float ClampToUnitInterval(float u) { return std::clamp(u, 0.0f, 0x1.fffffep-1f); }

// The azimuth φ of w as the fraction φ / 2π in [0, 1): the inverse of the
// φ = 2π·u1 that the spherical warps share.
inline float AzimuthFraction(Vec3 w) {
  float phi = std::atan2(w.y, w.x);
  if (phi < 0) phi += 2 * kPi;
  return ClampToUnitInterval(phi / (2 * kPi));
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

// Area density: uniform over the unit disk. The rim is widened by a few
// ulps so that points SampleConcentricDisk rounds just outside still count.
inline float ConcentricDiskPdf(float x, float y) {
  return x * x + y * y <= 1.0f + 1e-6f ? kInvPi : 0.0f;
}

// Inverse of SampleConcentricDisk. The disk splits into four quarters,
// the angles within π/4 of an axis: on the quarters around the x axis the
// square's coordinate a is ±r and b/a grows linearly with φ, on those
// around the y axis the roles swap. Points outside the disk map to the
// square's edge.
inline std::array<float, 2> InvertConcentricDisk(float x, float y) {
  const float r = std::sqrt(x * x + y * y);
  float phi = std::atan2(y, x);
  // φ in [-π/4, 7π/4), so that each quarter is one interval.
  if (phi < -kPi / 4) phi += 2 * kPi;
  float a, b;
  if (phi < kPi / 4) {
    a = r;
    b = r * phi * (4 / kPi);
  } else if (phi < 3 * kPi / 4) {
    b = r;
    a = r * (kPi / 2 - phi) * (4 / kPi);
  } else if (phi < 5 * kPi / 4) {
    // Here r = a < 0 and the angle SampleConcentricDisk forms is φ - π.
    a = -r;
    b = -r * (phi - kPi) * (4 / kPi);
  } else {
    b = -r;
    a = -r * (3 * kPi / 2 - phi) * (4 / kPi);
  }
  return {ClampToUnitInterval(0.5f * (a + 1.0f)), ClampToUnitInterval(0.5f * (b + 1.0f))};
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

// Inverse of SampleCosineHemisphere: the projection onto the disk, then
// the disk's inverse.
inline std::array<float, 2> InvertCosineHemisphere(Vec3 w) {
  return InvertConcentricDisk(w.x, w.y);
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

inline std::array<float, 2> InvertUniformHemisphere(Vec3 w) {
  return {ClampToUnitInterval(w.z), AzimuthFraction(w)};
}

// Uniform over the sphere: cos θ is uniform in [-1, 1].
inline Vec3 SampleUniformSphere(float u0, float u1) {
  const float cos_theta = 1.0f - 2.0f * u0;
  return SphericalDirection(SinFromCos(cos_theta), cos_theta, 2 * kPi * u1);
}

inline float UniformSpherePdf() { return 1.0f / (4 * kPi); }

inline std::array<float, 2> InvertUniformSphere(Vec3 w) {
  return {ClampToUnitInterval(0.5f * OneMinusCosTheta(w)), AzimuthFraction(w)};
}

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

// Inverse of SampleUniformCone: u0 = (1 - cos θ) / (1 - cos θmax), with
// 1 - cos θ taken from sin θ so that a narrow cone keeps its precision.
inline std::array<float, 2> InvertUniformCone(Vec3 w, float cos_theta_max) {
  return {ClampToUnitInterval(OneMinusCosTheta(w) / (1.0f - cos_theta_max)), AzimuthFraction(w)};
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

// Clarberg's equal-area map of the square [0, 1]² onto the unit sphere
// (pbrt-v4's EqualAreaSquareToSphere): each cell of a square image stands
// for the same solid angle, 4π over the cell count; +z at the centre, −z
// at the corners.
inline Vec3 EqualAreaSquareToSphere(float px, float py) {
  const float u = 2 * px - 1, v = 2 * py - 1;
  const float up = std::abs(u), vp = std::abs(v);
  const float signed_distance = 1 - (up + vp);
  const float r = 1 - std::abs(signed_distance);
  const float phi = (r == 0 ? 1 : (vp - up) / r + 1) * kPi / 4;
  const float z = std::copysign(1 - r * r, signed_distance);
  const float s = r * std::sqrt(std::max(0.0f, 2 - r * r));
  return {std::copysign(std::cos(phi), u) * s, std::copysign(std::sin(phi), v) * s, z};
}

// Inverse of EqualAreaSquareToSphere, for unit directions.
inline std::array<float, 2> EqualAreaSphereToSquare(Vec3 d) {
  const float x = std::abs(d.x), y = std::abs(d.y), z = std::abs(d.z);
  const float r = std::sqrt(std::max(0.0f, 1 - z));
  const float a = std::max(x, y), b = a > 0 ? std::min(x, y) / a : 0.0f;
  float phi = std::atan(b) * (2 / kPi);
  if (x < y) phi = 1 - phi;
  float v = phi * r, u = r - v;
  if (d.z < 0) {
    std::swap(u, v);
    u = 1 - u, v = 1 - v;
  }
  u = std::copysign(u, d.x), v = std::copysign(v, d.y);
  return {0.5f * (u + 1), 0.5f * (v + 1)};
}

// Area density on a triangle of the given area.
inline float UniformTrianglePdf(float area) { return 1.0f / area; }

// Inverse of SampleUniformTriangle. Its two branches meet on b0 = b1:
// u0 < u1 gives b1 > b0, and then b0 = u0 / 2, b0 + b1 = u1; otherwise
// b1 = u1 / 2, b0 + b1 = u0. Only b0 and b1 are read.
inline std::array<float, 2> InvertUniformTriangle(float b0, float b1) {
  if (b1 > b0) return {ClampToUnitInterval(2 * b0), ClampToUnitInterval(b0 + b1)};
  return {ClampToUnitInterval(b0 + b1), ClampToUnitInterval(2 * b1)};
}

// The solid angle of the spherical triangle of unit directions a, b, c
// (Van Oosterom & Strackee's formula).
inline float SphericalTriangleArea(Vec3 a, Vec3 b, Vec3 c) {
  return std::abs(2 * std::atan2(Dot(a, Cross(b, c)), 1 + Dot(a, b) + Dot(a, c) + Dot(b, c)));
}

// Triangle v0 v1 v2 as seen from a point: the unit directions to its
// corners and the solid angle they span; zero from a corner. Made once
// for both the choice of how to sample it and the sample.
struct SphericalTriangle {
  Vec3 a, b, c;
  float area = 0;

  static SphericalTriangle Seen(const Vec3 v[3], Vec3 p) {
    const Vec3 to_a = v[0] - p, to_b = v[1] - p, to_c = v[2] - p;
    if (!(Length(to_a) > 0 && Length(to_b) > 0 && Length(to_c) > 0)) return {};
    SphericalTriangle seen{Normalize(to_a), Normalize(to_b), Normalize(to_c)};
    seen.area = SphericalTriangleArea(seen.a, seen.b, seen.c);
    return seen;
  }
};

// Uniform in the solid angle that triangle v0 v1 v2 subtends from p
// (Arvo 1995, in pbrt-v4's formulation), `seen` being the triangle as
// seen from p: the barycentrics (of v0, v1, v2) of the point the sampled
// direction meets, density 1/Ω in solid angle. False for a triangle seen
// edge-on or from a vertex.
inline bool SampleSphericalTriangle(const Vec3 v[3], Vec3 p, const SphericalTriangle& seen, float u0, float u1,
                                    std::array<float, 3>& barycentrics) {
  const Vec3 a = seen.a, b = seen.b, c = seen.c;
  const Vec3 n_ab = Cross(a, b), n_bc = Cross(b, c), n_ca = Cross(c, a);
  if (!(Dot(n_ab, n_ab) > 0 && Dot(n_bc, n_bc) > 0 && Dot(n_ca, n_ca) > 0)) return false;
  // The area (as the density has it) and the angle at a; a sub-triangle
  // of area u0 times the whole is cut off along b c. Its area beyond π,
  // the angle's excess, enters only through sine and cosine:
  // sin(π + x) = −sin x, cos(π + x) = −cos x.
  const float area = seen.area;
  if (!(area > 0)) return false;
  const float cos_alpha = std::clamp(Dot(Normalize(n_ab), -Normalize(n_ca)), -1.0f, 1.0f);
  const float sin_alpha = std::sqrt(1 - cos_alpha * cos_alpha);
  const float sin_sub = -std::sin(u0 * area), cos_sub = -std::cos(u0 * area);
  const float sin_phi = sin_sub * cos_alpha - cos_sub * sin_alpha;
  const float cos_phi = cos_sub * cos_alpha + sin_sub * sin_alpha;
  const float k1 = cos_phi + cos_alpha, k2 = sin_phi - sin_alpha * Dot(a, b);
  float cos_bp = (k2 + (k2 * cos_phi - k1 * sin_phi) * cos_alpha) / ((k2 * sin_phi + k1 * cos_phi) * sin_alpha);
  cos_bp = std::clamp(std::isfinite(cos_bp) ? cos_bp : 1.0f, -1.0f, 1.0f);
  // c' on the arc from a to c, then a direction uniform in cos along b c'.
  const Vec3 c_off_a = Normalize(c - a * Dot(c, a));
  const Vec3 cp = a * cos_bp + c_off_a * std::sqrt(std::max(0.0f, 1 - cos_bp * cos_bp));
  const float cos_theta = 1 - u1 * (1 - Dot(cp, b));
  const Vec3 across = cp - b * Dot(cp, b);
  if (!(Dot(across, across) > 0)) return false;
  const Vec3 w = b * cos_theta + Normalize(across) * std::sqrt(std::max(0.0f, 1 - cos_theta * cos_theta));
  // Where w meets the triangle's plane (Möller–Trumbore's barycentrics).
  const Vec3 e1 = v[1] - v[0], e2 = v[2] - v[0], s1 = Cross(w, e2);
  const float divisor = Dot(s1, e1);
  if (!(std::abs(divisor) > 0)) return false;
  const Vec3 s = p - v[0];
  float b1 = std::clamp(Dot(s, s1) / divisor, 0.0f, 1.0f), b2 = std::clamp(Dot(w, Cross(s, e1)) / divisor, 0.0f, 1.0f);
  if (b1 + b2 > 1) {
    const float sum = b1 + b2;
    b1 /= sum, b2 /= sum;
  }
  barycentrics = {1 - b1 - b2, b1, b2};
  return true;
}

// The Phong lobe: density ∝ cos^n θ around +z; cos θ = u^(1/(n+1)) inverts
// its marginal CDF in cos θ.
inline Vec3 SamplePhongLobe(float u0, float u1, float exponent) {
  const float cos_theta = std::pow(u0, 1.0f / (exponent + 1.0f));
  return SphericalDirection(SinFromCos(cos_theta), cos_theta, 2 * kPi * u1);
}

inline float PhongLobePdf(float cos_theta, float exponent) {
  return cos_theta > 0 ? (exponent + 1.0f) / (2 * kPi) * std::pow(cos_theta, exponent) : 0.0f;
}

// Inverse of SamplePhongLobe: u0 = cos^(n+1) θ, evaluated as
// exp((n+1)·log(1 - (1 - cos θ))) in double, because for a sharp lobe the
// float cos θ is too coarse near 1 to carry u0.
inline std::array<float, 2> InvertPhongLobe(Vec3 w, float exponent) {
  if (w.z <= 0) return {0.0f, AzimuthFraction(w)};
  const double u0 = std::exp((double(exponent) + 1.0) * std::log1p(-double(OneMinusCosTheta(w))));
  return {ClampToUnitInterval(float(u0)), AzimuthFraction(w)};
}

// --- GGX microfacet normals -------------------------------------------------
// The GGX (Trowbridge–Reitz) distribution with anisotropic roughness αx
// along x and αy along y, and Heitz's sampling of the normals visible
// from a direction wi ("Sampling the GGX Distribution of Visible Normals",
// JCGT 2018). Microfacet normals m lie in the upper hemisphere; wi must
// too (callers flip a direction arriving from below).

// D(m) = 1 / (π αx αy ((mx/αx)² + (my/αy)² + mz²)²), normalised so that
// ∫ D(m) cos θm dωm = 1 (the microfacets' projected area is the surface's).
inline float GgxDistribution(Vec3 m, float alpha_x, float alpha_y) {
  if (m.z <= 0) return 0.0f;
  const float x = m.x / alpha_x, y = m.y / alpha_y;
  const float e = x * x + y * y + m.z * m.z;
  return 1.0f / (kPi * alpha_x * alpha_y * e * e);
}

// Smith's masking G1(w) = 1 / (1 + Λ(w)) with the GGX
// Λ(w) = (-1 + √(1 + (αx² wx² + αy² wy²) / wz²)) / 2: the fraction of the
// microfacets' projected area toward w that is not hidden by others.
// 0 at and below the horizon. Written as 2 wz / (wz + √(wz² + αx² wx² +
// αy² wy²)), the same value without dividing by wz², which overflows at
// grazing angles.
inline float GgxSmithG1(Vec3 w, float alpha_x, float alpha_y) {
  if (w.z <= 0) return 0.0f;
  const float ax = alpha_x * w.x, ay = alpha_y * w.y;
  return 2.0f * w.z / (w.z + std::sqrt(w.z * w.z + ax * ax + ay * ay));
}

// The distribution of visible normals, a density over solid angle of m:
// D_wi(m) = G1(wi) · max(0, wi·m) · D(m) / wi.z — normals weighted by the
// area they show to wi, over the microsurface's projected area toward wi,
// which is wi.z / G1(wi).
inline float GgxVisibleNormalPdf(Vec3 wi, Vec3 m, float alpha_x, float alpha_y) {
  if (wi.z <= 0) return 0.0f;
  const float cos_wi_m = Dot(wi, m);
  if (cos_wi_m <= 0) return 0.0f;
  return GgxSmithG1(wi, alpha_x, alpha_y) * cos_wi_m * GgxDistribution(m, alpha_x, alpha_y) /
         wi.z;
}

// Samples m with density GgxVisibleNormalPdf. GGX normals are those of
// the upper half of an ellipsoid with radii (1/αx, 1/αy, 1); scaling
// space by (αx, αy, 1) makes it the unit hemisphere and takes wi to vh.
// The hemisphere's normals visible from vh are distributed like the points
// of its projection along vh: a unit disk made of the projected half of
// the dome (a half-disk) and of the base's projected half (a half-ellipse
// squashed by cos θ of vh). So: sample the unit disk, squash the half that
// stands for the ellipse, lift the point onto the hemisphere along vh, and
// take the normal back to the ellipsoid.
inline Vec3 SampleGgxVisibleNormal(Vec3 wi, float alpha_x, float alpha_y, float u0, float u1) {
  const Vec3 vh = Normalize(Vec3(alpha_x * wi.x, alpha_y * wi.y, wi.z));
  // A basis (t1, t2, vh); t1 is horizontal, arbitrary at normal incidence.
  const float len2 = vh.x * vh.x + vh.y * vh.y;
  const Vec3 t1 = len2 > 0 ? Vec3(-vh.y, vh.x, 0.0f) / std::sqrt(len2) : Vec3(1.0f, 0.0f, 0.0f);
  const Vec3 t2 = Cross(vh, t1);
  // Uniform point of the unit disk (polar map, as in the paper).
  const float r = std::sqrt(u0);
  const float phi = 2 * kPi * u1;
  const float p1 = r * std::cos(phi);
  float p2 = r * std::sin(phi);
  // The half p2 < 0 covers the ellipse of half-height cos θ = vh.z: map
  // p2 from [-h, h] (h = √(1 - p1²), the disk's half-chord) onto
  // [-h·vh.z, h], which leaves p2 = h fixed and scales the rest linearly.
  const float s = 0.5f * (1.0f + vh.z);
  const float h = std::sqrt(std::max(0.0f, 1.0f - p1 * p1));
  p2 = (1.0f - s) * h + s * p2;
  // The point of the hemisphere above (p1, p2) along vh.
  const Vec3 nh = p1 * t1 + p2 * t2 + std::sqrt(std::max(0.0f, 1.0f - p1 * p1 - p2 * p2)) * vh;
  // Back to the ellipsoid, the scaling (1/αx, 1/αy, 1): normals transform
  // by its inverse transpose.
  return Normalize(Vec3(alpha_x * nh.x, alpha_y * nh.y, std::max(0.0f, nh.z)));
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
