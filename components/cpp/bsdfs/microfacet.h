// Pieces the microfacet and coated surface models share (bsdfs/rough*.cc,
// conductor.cc, plastic.cc): their roughness property, Smith's joint
// masking-shadowing, reflection and refraction about a microfacet normal,
// the Fresnel factor of a conductor and the hemispherical averages the
// coated models need. Indices of refraction are read in
// surface_properties.h.
// GGX's D, its G1 and the sampling of visible normals are in yarf/warps.h.
//
// Microfacet normals m lie in the upper hemisphere (m.z > 0); +z is the
// outside (ext_ior) side of a dielectric.
#pragma once

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <span>
#include <string>
#include <utility>

#include "yarf/error.h"
#include "yarf/properties.h"
#include "yarf/texture.h"
#include "yarf/vecmath.h"
#include "yarf/warps.h"

namespace yarf::microfacet {

// --- Roughness -------------------------------------------------------------

// Roughness below this is raised to it: a GGX lobe narrower than float
// directions can resolve is a mirror in all but name.
inline constexpr float kMinAlpha = 1e-4f;

// GGX roughness along the shading frame's x (alpha_u) and y (alpha_v).
struct Roughness {
  float alpha_x = 0.1f, alpha_y = 0.1f;
};

inline float RequireAlpha(double alpha, const std::string& property) {
  if (!(alpha > 0.0 && std::isfinite(alpha)))
    throw Error("property '" + property + "' must be a finite number > 0");
  return std::max(float(alpha), kMinAlpha);
}

// A roughness property: a finite number > 0 (raised to kMinAlpha), or a
// texture whose values are clamped to ≥ kMinAlpha where it is looked up.
inline TexturedValue ReadAlpha(const Properties& props, const std::string& property,
                               double fallback) {
  if (auto texture = props.TextureOf(property))
    return TexturedValue(std::move(texture)).Clamped(kMinAlpha, std::numeric_limits<float>::max());
  return TexturedValue(RequireAlpha(props.Float(property, fallback), property));
}

// The roughness at a call's points (TexturedRoughness::At).
class PointRoughness {
 public:
  PointRoughness(PointValues<float> x, PointValues<float> y) : x_(std::move(x)), y_(std::move(y)) {}
  Roughness operator[](size_t k) const { return {x_[k], y_[k]}; }

 private:
  PointValues<float> x_, y_;
};

// Roughness whose α may vary over the surface (textures).
struct TexturedRoughness {
  TexturedValue alpha_x, alpha_y;

  // At the [N,2] uv of a surface call.
  PointRoughness At(const yarf::SurfacePoints& at) const {
    return {alpha_x.FloatsAt(at), alpha_y.FloatsAt(at)};
  }
};

// Reads Mitsuba's roughness properties: 'alpha' (isotropic, default
// `fallback`), or 'alpha_u' and 'alpha_v' together when the model is
// `anisotropic`, each a number or a texture; and 'distribution', which
// may only name "ggx", the one distribution here (Mitsuba's default is
// Beckmann: a scene that relies on it must say "ggx" to mean this model).
inline TexturedRoughness ReadTexturedRoughness(const Properties& props, double fallback,
                                               bool anisotropic) {
  const std::string distribution = props.String("distribution", "ggx");
  if (distribution != "ggx")
    throw Error("property 'distribution' must be \"ggx\" (the only microfacet distribution), "
                "not \"" + distribution + "\"");
  const bool has_u = props.Has("alpha_u"), has_v = props.Has("alpha_v");
  if (!has_u && !has_v) {
    const TexturedValue alpha = ReadAlpha(props, "alpha", fallback);
    return {alpha, alpha};
  }
  const std::string given = has_u ? "alpha_u" : "alpha_v";
  if (!anisotropic)
    throw Error("property '" + given + "': this model is isotropic, give its roughness as 'alpha'");
  if (props.Has("alpha"))
    throw Error("properties 'alpha' and '" + given + "' exclude each other");
  if (!has_u || !has_v)
    throw Error(std::string("property '") + (has_u ? "alpha_v" : "alpha_u") +
                "' is missing: anisotropic roughness needs both 'alpha_u' and 'alpha_v'");
  return {ReadAlpha(props, "alpha_u", fallback), ReadAlpha(props, "alpha_v", fallback)};
}

// The same for a model whose roughness is one number over the whole
// surface (tables built for it at construction): a texture is an Error.
inline Roughness ReadRoughness(const Properties& props, double fallback, bool anisotropic) {
  const TexturedRoughness roughness = ReadTexturedRoughness(props, fallback, anisotropic);
  for (const char* property : {"alpha", "alpha_u", "alpha_v"})
    if (props.TextureOf(property))
      throw Error("property '" + std::string(property) +
                  "' must be a number: this model's roughness cannot vary over the surface");
  return {roughness.alpha_x.Constant().x, roughness.alpha_y.Constant().x};
}

// --- Geometry about a microfacet -------------------------------------------

// Mirror direction of w about the unit normal m.
inline Vec3 ReflectAbout(Vec3 w, Vec3 m) { return 2.0f * Dot(w, m) * m - w; }

// The direction in which light arriving along -wi continues through a
// smooth facet of unit normal m (warps.h's Refract, about m instead of
// +z). eta = n(m's back side) / n(m's front side). False on total
// internal reflection.
inline bool RefractAbout(Vec3 wi, Vec3 m, float eta, Vec3* wt) {
  const float cos_i = Dot(wi, m);
  const float eta_rel = cos_i >= 0 ? eta : 1.0f / eta;
  const float sin2_t = std::max(0.0f, 1.0f - cos_i * cos_i) / (eta_rel * eta_rel);
  if (sin2_t >= 1.0f) return false;
  const float cos_t = std::sqrt(1.0f - sin2_t);
  // Tangential part shrinks by 1/eta_rel (Snell); the normal part is
  // cos θt on the far side of the facet.
  *wt = Normalize(-wi / eta_rel + (cos_i / eta_rel - std::copysign(cos_t, cos_i)) * m);
  return true;
}

// --- Masking and shadowing -------------------------------------------------

// GGX's G1 of a direction on either side of the surface (warps.h's
// GgxSmithG1 of w mirrored to the upper side).
inline float SmithG1(Vec3 w, float alpha_x, float alpha_y) {
  return GgxSmithG1(Vec3(w.x, w.y, std::abs(w.z)), alpha_x, alpha_y);
}

// Smith's joint masking-shadowing, in its height-correlated form (Heitz,
// "Understanding the masking-shadowing function", JCGT 2014, eq. 99):
// G2 = 1 / (1 + Λ(wi) + Λ(wo)), more accurate than the separable
// G1(wi)·G1(wo) (which Mitsuba uses), as a microfacet seen from wi is more
// likely seen from wo when both lie high. pbrt-v4 uses this form for
// reflection and transmission alike, as here. With Λ(w) = (s - |wz|) /
// (2|wz|), s = √(wz² + αx² wx² + αy² wy²), it is 2|zi||zo| / (|zo| si +
// |zi| so), with no division by cos θ. Symmetric in wi and wo; 1 as α → 0.
inline float SmithG2(Vec3 wi, Vec3 wo, float alpha_x, float alpha_y) {
  const float zi = std::abs(wi.z), zo = std::abs(wo.z);
  if (zi == 0 || zo == 0) return 0.0f;
  const auto s = [&](Vec3 w, float z) {
    const float ax = alpha_x * w.x, ay = alpha_y * w.y;
    return std::sqrt(z * z + ax * ax + ay * ay);
  };
  return 2.0f * zi * zo / (zo * s(wi, zi) + zi * s(wo, zo));
}

// --- Fresnel factors -------------------------------------------------------

// Fresnel reflectance of unpolarised light at the surface of a conductor
// of complex index η + iκ relative to the outside medium, at incidence
// cos θi (clamped to [0, 1]): the exact formula of a dielectric with a
// complex index (Born & Wolf §14.2). κ = 0 gives FresnelDielectric; η = 0,
// κ = 1 gives 1 at every angle (Mitsuba's perfect mirror).
inline float FresnelConductor(float cos_i, float eta, float k) {
  using Complex = std::complex<float>;
  cos_i = std::clamp(cos_i, 0.0f, 1.0f);
  const Complex n(eta, k);
  const float sin2_i = 1.0f - cos_i * cos_i;
  const Complex cos_t = std::sqrt(Complex(1.0f) - sin2_i / (n * n));
  const Complex r_parallel = (n * cos_i - cos_t) / (n * cos_i + cos_t);
  const Complex r_perpendicular = (cos_i - n * cos_t) / (cos_i + n * cos_t);
  return std::min(1.0f, 0.5f * (std::norm(r_parallel) + std::norm(r_perpendicular)));
}

// Per RGB channel, each with its own complex index.
inline Vec3 FresnelConductor(float cos_i, Vec3 eta, Vec3 k) {
  return {FresnelConductor(cos_i, eta.x, k.x), FresnelConductor(cos_i, eta.y, k.y),
          FresnelConductor(cos_i, eta.z, k.z)};
}

// The diffuse Fresnel reflectance F_dr(η) = 2 ∫ F(μ) μ dμ: the fraction of
// uniform diffuse light arriving from the side where the relative index
// (far side over near side) is eta that the smooth interface reflects.
// Computed numerically (Mitsuba fits a polynomial instead) by the midpoint
// rule in s = μ², where it reads ∫ F(√s) ds. For eta < 1 (light from the
// dense side, with total internal reflection) through the reciprocity of
// transmission, 1 - F_dr(η) = (1 - F_dr(1/η)) η², which the coated
// models rely on to conserve energy exactly.
inline float FresnelDiffuseReflectance(float eta) {
  if (eta < 1.0f) return 1.0f - (1.0f - FresnelDiffuseReflectance(1.0f / eta)) * eta * eta;
  constexpr int kSteps = 4096;
  double sum = 0;
  for (int i = 0; i < kSteps; ++i)
    sum += FresnelDielectric(std::sqrt((i + 0.5f) / kSteps), eta);
  return float(sum / kSteps);
}

// The directional albedo of an isotropic GGX dielectric interface's
// reflection, ∫ F(wi·m) D(m) G2 / (4 cos θi cos θo) cos θo dωo at incidence
// cos θi from the side where the relative index is eta: the mean of
// F · G2 / G1(wi) over visible normals, on a strata × strata grid of
// their sampling (deterministic). Normals that reflect below the horizon
// contribute nothing.
inline float RoughDielectricReflectance(float cos_theta, float alpha, float eta,
                                        int strata = 64) {
  cos_theta = std::clamp(cos_theta, 1e-4f, 1.0f);
  const Vec3 wi(SinFromCos(cos_theta), 0.0f, cos_theta);
  const float g1 = GgxSmithG1(wi, alpha, alpha);
  double sum = 0;
  for (int i = 0; i < strata; ++i)
    for (int j = 0; j < strata; ++j) {
      const Vec3 m = SampleGgxVisibleNormal(wi, alpha, alpha, (i + 0.5f) / strata,
                                            (j + 0.5f) / strata);
      const Vec3 wo = ReflectAbout(wi, m);
      if (wo.z <= 0) continue;
      sum += FresnelDielectric(Dot(wi, m), eta) * SmithG2(wi, wo, alpha, alpha) / g1;
    }
  return float(sum / (double(strata) * strata));
}

}  // namespace yarf::microfacet
