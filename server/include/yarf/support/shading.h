// The frame surface models see at a hit, and the rules that keep
// interpolated (shading) normals from leaking light through a surface:
// scatterings the geometric and the shading normal disagree on carry
// nothing, and importance transport takes Veach's correction (Veach 1997,
// §5.3), as pbrt-v3 and Mitsuba do.
#pragma once

#include <algorithm>
#include <cmath>

#include "yarf/geometry.h"

namespace yarf {

// Whether two vectors are the same bit for bit (a flat surface's shading
// normal is its geometric one).
inline bool SameVector(Vec3 a, Vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

// The local frame of the surface models at `hit`: z its shading normal,
// x along ∂p/∂u where it is not parallel to it (so anisotropic models
// follow the parameterisation). It depends on the point alone, not on the
// direction a path arrives from, so that paths from the camera and from
// the lights see one and the same BSDF (a view-dependent bend of the
// normal would make them estimate different integrals).
inline Frame ShadingFrame(const Hit& hit) {
  const Vec3 n = hit.shading_normal;
  const Vec3 s = hit.dpdu - n * Dot(n, hit.dpdu);
  const float length = Length(s);
  if (!(length > 1e-12f) || !std::isfinite(length)) return Frame(n);
  Frame frame(n);
  frame.s = s / length;
  frame.t = Cross(n, frame.s);
  return frame;
}

// The footprint (du/dx, dv/dx, du/dy, dv/dy) of a point whose position
// moves by dpdx, dpdy from one film sample to the next: the least-squares
// solution of dpdx = ∂p/∂u·du/dx + ∂p/∂v·dv/dx (likewise y). Zero for a
// degenerate parameterisation; bounded, so that a texture's filter stays
// finite.
inline void UvFootprint(Vec3 dpdu, Vec3 dpdv, Vec3 dpdx, Vec3 dpdy, float footprint[4]) {
  const float uu = Dot(dpdu, dpdu), uv = Dot(dpdu, dpdv), vv = Dot(dpdv, dpdv);
  const float det = uu * vv - uv * uv;
  const float inverse = det > 0 && std::isfinite(det) ? 1 / det : 0.0f;
  const Vec3 steps[2] = {dpdx, dpdy};
  for (int i = 0; i < 2; ++i) {
    const float bu = Dot(dpdu, steps[i]), bv = Dot(dpdv, steps[i]);
    const float du = (vv * bu - uv * bv) * inverse, dv = (uu * bv - uv * bu) * inverse;
    constexpr float kLargest = 1e8f;
    footprint[2 * i] = std::isfinite(du) ? std::clamp(du, -kLargest, kLargest) : 0.0f;
    footprint[2 * i + 1] = std::isfinite(dv) ? std::clamp(dv, -kLargest, kLargest) : 0.0f;
  }
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
