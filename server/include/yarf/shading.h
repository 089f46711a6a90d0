// The frame surface models see at a hit, and the rules that keep
// interpolated (shading) normals from leaking light or darkening grazing
// views: Veach 1997 §5.3 for importance transport, and a bend of the
// shading normal toward the geometric one where a view would reflect
// below the surface (as Cycles' valid-reflection rule does).
#pragma once

#include <algorithm>
#include <cmath>

#include "yarf/geometry.h"

namespace yarf {

// Whether two vectors are the same bit for bit (a flat surface's shading
// normal is its geometric one).
inline bool SameVector(Vec3 a, Vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

// ns bent toward ng (both unit, on wi's side) until the mirror reflection
// of wi lies above the surface by the margin ShadingNormalSeenFrom names.
inline Vec3 BentShadingNormal(Vec3 ng, Vec3 ns, Vec3 wi) {
  const float iz = Dot(wi, ng);
  const float threshold = std::min(0.9f * iz, 0.01f);
  if (2 * Dot(ns, wi) * Dot(ns, ng) - iz >= threshold) return ns;
  // In the plane of ng and the part of ns across it, ns = sin θ·x + cos θ·ng
  // reflects wi to height ix·sin 2θ + iz·cos 2θ = A·cos(2θ − φ). It is above
  // the threshold at θ = 0 (ng itself) and below at ns's own θ; the normal
  // used is where it crosses the threshold between them.
  const Vec3 across = ns - ng * Dot(ns, ng);
  const float across_length = Length(across);
  if (!(across_length > 1e-6f)) return ng;
  const Vec3 x = across / across_length;
  const float ix = Dot(wi, x);
  const float a = std::sqrt(ix * ix + iz * iz), phi = std::atan2(ix, iz);
  const float theta_ns = std::atan2(across_length, Dot(ns, ng));
  const float spread = std::acos(std::clamp(threshold / a, -1.0f, 1.0f));
  float theta = 0;
  for (const float root : {0.5f * (phi + spread), 0.5f * (phi - spread)})
    if (root > theta && root < theta_ns) theta = root;
  return Normalize(x * std::sin(theta) + ng * std::cos(theta));
}

// The shading normal a path arriving from direction `wi` (unit, away from
// the surface toward where the path came from) sees at `hit`: its
// shading normal, bent toward the geometric normal just enough that the
// mirror reflection of wi leaves the surface on wi's side
// (Dot(reflection, ng) at least min(0.9·Dot(wi, ng), 0.01) there). It
// stays on the outward side, as hit.normal, so that models which tell
// inside from outside (dielectrics) still can.
inline Vec3 ShadingNormalSeenFrom(const Hit& hit, Vec3 wi) {
  if (SameVector(hit.shading_normal, hit.normal)) return hit.normal;  // flat: nothing to bend
  const float side = Dot(wi, hit.normal) >= 0 ? 1.0f : -1.0f;
  return BentShadingNormal(hit.normal * side, hit.shading_normal * side, wi) * side;
}

// The local frame of the surface models at `hit` for a path arriving
// from `wi`: z the shading normal seen from wi, x along ∂p/∂u where it is
// not parallel to it (so anisotropic models follow the parameterisation).
inline Frame ShadingFrame(const Hit& hit, Vec3 wi) {
  const Vec3 n = ShadingNormalSeenFrom(hit, wi);
  const Vec3 s = hit.dpdu - n * Dot(n, hit.dpdu);
  const float length = Length(s);
  if (!(length > 1e-12f) || !std::isfinite(length)) return Frame(n);
  Frame frame(n);
  frame.s = s / length;
  frame.t = Cross(n, frame.s);
  return frame;
}

// Whether a scattering from wi to wo (world, unit) is a reflection or a
// transmission alike for the geometric normal ng and in the shading frame
// (local z of each): where they disagree the value is 0, or light would
// pass through a reflecting surface or around a transmitting one.
inline bool SidesAgree(Vec3 wi, Vec3 wo, Vec3 ng, float wi_local_z, float wo_local_z) {
  return (Dot(wi, ng) * Dot(wo, ng) > 0) == (wi_local_z * wo_local_z > 0);
}

// Importance transport with shading normals (Veach 1997, eq. 5.19): a
// path from the lights that arrived from wi and goes on to wo carries
// f·|wo·ns|/pdf times |wi·ns|·|wo·ng| / (|wi·ng|·|wo·ns|), so that the
// adjoint stays the adjoint. Radiance transport needs no factor.
inline float ImportanceShadingFactor(Vec3 wi, Vec3 wo, Vec3 ng, Vec3 ns) {
  const float denominator = std::abs(Dot(wi, ng)) * std::abs(Dot(wo, ns));
  if (!(denominator > 0)) return 0;
  return std::abs(Dot(wi, ns)) * std::abs(Dot(wo, ng)) / denominator;
}

}  // namespace yarf
