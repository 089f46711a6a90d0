// Pieces the microfacet and coated surface models share (bsdfs/rough*.cc,
// conductor.cc, plastic.cc): their roughness property and its parameters,
// Smith's joint masking-shadowing, reflection and refraction about a
// microfacet normal, the Fresnel factor of a conductor and the
// hemispherical averages the coated models need. Indices of refraction
// are read in surface_properties.h.
// Two distributions of microfacet normals: GGX (its D, G1 and sampling of
// visible normals are in yarf/support/warps.h) and Beckmann (Mitsuba's default),
// each anisotropic, with Smith's masking and sampling of visible normals.
//
// Microfacet normals m lie in the upper hemisphere (m.z > 0); +z is the
// outside (ext_ior) side of a dielectric.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "yarf/error.h"
#include "yarf/parameters.h"
#include "yarf/properties.h"
#include "yarf/texture.h"
#include "yarf/vecmath.h"
#include "yarf/support/warps.h"

namespace yarf::microfacet {

// --- Roughness -------------------------------------------------------------

// Roughness below this is raised to it: a GGX lobe narrower than float
// directions can resolve is a mirror in all but name.
inline constexpr float kMinAlpha = 1e-4f;

enum class Distribution { kGgx, kBeckmann };

// Roughness along the shading frame's x (alpha_u) and y (alpha_v), of
// either distribution.
struct Roughness {
  float alpha_x = 0.1f, alpha_y = 0.1f;
  Distribution distribution = Distribution::kGgx;
};

// The 'distribution' property: "ggx" (the default) or "beckmann".
inline Distribution ReadDistribution(const Properties& props) {
  const std::string name = props.String("distribution", "ggx");
  if (name == "ggx") return Distribution::kGgx;
  if (name == "beckmann") return Distribution::kBeckmann;
  throw Error("property 'distribution' must be \"ggx\" or \"beckmann\", not \"" + name + "\"");
}

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
  PointRoughness(PointValues<float> x, PointValues<float> y, Distribution distribution)
      : x_(std::move(x)), y_(std::move(y)), distribution_(distribution) {}
  Roughness operator[](size_t k) const { return {x_[k], y_[k], distribution_}; }

 private:
  PointValues<float> x_, y_;
  Distribution distribution_;
};

// Roughness whose α may vary over the surface (textures).
struct TexturedRoughness {
  TexturedValue alpha_x, alpha_y;
  Distribution distribution = Distribution::kGgx;

  // At the [N,2] uv of a surface call.
  PointRoughness At(const yarf::SurfacePoints& at) const {
    return {alpha_x.FloatsAt(at), alpha_y.FloatsAt(at), distribution};
  }
};

// Reads Mitsuba's roughness properties: 'alpha' (isotropic, default
// `fallback`), or 'alpha_u' and 'alpha_v' together when the model is
// `anisotropic`, each a number or a texture; and 'distribution', "ggx"
// (the default here) or "beckmann" (Mitsuba's default, which its
// importer passes on).
inline TexturedRoughness ReadTexturedRoughness(const Properties& props, double fallback,
                                               bool anisotropic) {
  const Distribution distribution = ReadDistribution(props);
  const bool has_u = props.Has("alpha_u"), has_v = props.Has("alpha_v");
  if (!has_u && !has_v) {
    const TexturedValue alpha = ReadAlpha(props, "alpha", fallback);
    return {alpha, alpha, distribution};
  }
  const std::string given = has_u ? "alpha_u" : "alpha_v";
  if (!anisotropic)
    throw Error("property '" + given + "': this model is isotropic, give its roughness as 'alpha'");
  if (props.Has("alpha"))
    throw Error("properties 'alpha' and '" + given + "' exclude each other");
  if (!has_u || !has_v)
    throw Error(std::string("property '") + (has_u ? "alpha_v" : "alpha_u") +
                "' is missing: anisotropic roughness needs both 'alpha_u' and 'alpha_v'");
  return {ReadAlpha(props, "alpha_u", fallback), ReadAlpha(props, "alpha_v", fallback), distribution};
}

// The same for a model whose roughness is one number over the whole
// surface (tables built for it at construction): a texture is an Error.
inline Roughness ReadRoughness(const Properties& props, double fallback, bool anisotropic) {
  const TexturedRoughness roughness = ReadTexturedRoughness(props, fallback, anisotropic);
  for (const char* property : {"alpha", "alpha_u", "alpha_v"})
    if (props.TextureOf(property))
      throw Error("property '" + std::string(property) +
                  "' must be a number: this model's roughness cannot vary over the surface");
  return {roughness.alpha_x.Constant().x, roughness.alpha_y.Constant().x, roughness.distribution};
}

// The parameters ReadTexturedRoughness (`textured`) or ReadRoughness reads
// with these arguments. An anisotropic model's alpha has no declared
// default: it excludes alpha_u and alpha_v.
inline std::vector<Parameter> RoughnessParameters(double fallback, bool anisotropic, bool textured) {
  const auto number = [&](const char* name) {
    return Parameter::Of(name, textured ? ParameterType::kFloatTexture : ParameterType::kFloat).Min(0);
  };
  std::ostringstream alpha_default;
  alpha_default << fallback;
  std::vector<Parameter> out;
  if (anisotropic) {
    out.push_back(number("alpha").Doc("roughness α > 0; " + alpha_default.str() +
                                      " when neither it nor alpha_u, alpha_v is given"));
    out.push_back(number("alpha_u").Doc("roughness along the shading frame's x, with alpha_v, instead of alpha"));
    out.push_back(number("alpha_v").Doc("roughness along the shading frame's y, with alpha_u, instead of alpha"));
  } else {
    out.push_back(number("alpha").Default(fallback).Doc(textured ? "roughness α > 0"
                                                                 : "roughness α > 0, one number over the surface"));
  }
  out.push_back(Parameter::String("distribution")
                    .Default("ggx")
                    .Choices({"ggx", "beckmann"})
                    .Doc("the microfacet normals' distribution"));
  return out;
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

// --- The distributions -------------------------------------------------------

// The inverse error function by Giles' single-precision approximation
// ("Approximating the erfinv function", 2010): within a relative 4·10⁻⁷
// of the root over (-1, 1), as close as a Newton step on std::erf in
// single precision would bring it.
inline float ErfInv(float y) {
  y = std::clamp(y, -0.99999994f, 0.99999994f);
  float w = -std::log((1.0f - y) * (1.0f + y)), p;
  if (w < 5.0f) {
    w -= 2.5f;
    p = 2.81022636e-08f;
    for (float c : {3.43273939e-07f, -3.5233877e-06f, -4.39150654e-06f, 0.00021858087f, -0.00125372503f,
                    -0.00417768164f, 0.246640727f, 1.50140941f})
      p = c + p * w;
  } else {
    w = std::sqrt(w) - 3.0f;
    p = -0.000200214257f;
    for (float c : {0.000100950558f, 0.00134934322f, -0.00367342844f, 0.00573950773f, -0.0076224613f,
                    0.00943887047f, 1.00167406f, 2.83297682f})
      p = c + p * w;
  }
  return p * y;
}

// Beckmann's D: exp(-tan²θ (cos²φ/αx² + sin²φ/αy²)) / (π αx αy cos⁴θ).
inline float BeckmannDistribution(Vec3 m, float alpha_x, float alpha_y) {
  const float z2 = m.z * m.z;
  if (!(m.z > 0)) return 0.0f;
  const float x = m.x / alpha_x, y = m.y / alpha_y;
  return std::exp(-(x * x + y * y) / z2) / (kPi * alpha_x * alpha_y * z2 * z2);
}

// Smith's Λ of a direction on either side, for the distribution.
inline float SmithLambda(Vec3 w, const Roughness& r) {
  const float z = std::abs(w.z);
  const float ax = r.alpha_x * w.x, ay = r.alpha_y * w.y;
  const float tangent2 = ax * ax + ay * ay;  // α(w)² tan²θ · cos²θ
  if (z == 0) return std::numeric_limits<float>::infinity();
  if (tangent2 == 0) return 0.0f;
  if (r.distribution == Distribution::kGgx) return 0.5f * (std::sqrt(1.0f + tangent2 / (z * z)) - 1.0f);
  // Beckmann: a = 1 / (α(w) tan θ).
  const float a = z / std::sqrt(tangent2);
  return 0.5f * (std::erf(a) - 1.0f) + std::exp(-a * a) / (2.0f * a * std::sqrt(kPi));
}

// The distribution's D (its normal distribution function).
inline float Ndf(Vec3 m, const Roughness& r) {
  return r.distribution == Distribution::kGgx ? GgxDistribution(m, r.alpha_x, r.alpha_y)
                                               : BeckmannDistribution(m, r.alpha_x, r.alpha_y);
}

// --- Masking and shadowing -------------------------------------------------

// G1 and G2 (below) from the directions' Λ, for a caller that shares a
// direction's Λ between them.
inline float SmithG1OfLambda(float lambda) { return 1.0f / (1.0f + lambda); }
inline float SmithG2OfLambdas(float lambda_i, float lambda_o) { return 1.0f / (1.0f + lambda_i + lambda_o); }

// G1 of a direction on either side of the surface: 1 / (1 + Λ).
inline float SmithG1(Vec3 w, const Roughness& r) { return SmithG1OfLambda(SmithLambda(w, r)); }

// Smith's joint masking-shadowing, in its height-correlated form (Heitz,
// "Understanding the masking-shadowing function", JCGT 2014, eq. 99):
// G2 = 1 / (1 + Λ(wi) + Λ(wo)), more accurate than the separable
// G1(wi)·G1(wo) (which Mitsuba uses), as a microfacet seen from wi is more
// likely seen from wo when both lie high. pbrt-v4 uses this form for
// reflection and transmission alike, as here. Symmetric in wi and wo; 1
// as α → 0.
inline float SmithG2(Vec3 wi, Vec3 wo, const Roughness& r) {
  if (wi.z == 0 || wo.z == 0) return 0.0f;
  return SmithG2OfLambdas(SmithLambda(wi, r), SmithLambda(wo, r));
}

// --- Visible normals ---------------------------------------------------------

// The x slope of Beckmann's unit-roughness distribution visible from a
// direction at angle θi to the normal in the xz-plane (Heitz & d'Eon
// 2014): the inverse of its CDF at u0, found by Newton's method kept
// inside its bracket, in the variable b = erf(x). The y slope is Gaussian,
// independent of it (SampleBeckmannSlopeY).
inline float SampleBeckmannSlopeX(float cos_theta, float u0) {
  const float sin_theta = SinFromCos(cos_theta);
  const float tan_theta = sin_theta / std::max(cos_theta, 1e-7f);
  const float inv_sqrt_pi = 1.0f / std::sqrt(kPi);
  // The CDF ∝ 1 + b + tanθ/√π·exp(-x²), from b = -1 to erf(cot θ).
  float high = tan_theta > 0 ? std::erf(1.0f / tan_theta) : 1.0f, low = -1.0f;
  const float cot2 = tan_theta > 0 ? 1.0f / (tan_theta * tan_theta) : 0.0f;
  const float normalisation = 1.0f / (1.0f + high + inv_sqrt_pi * tan_theta * std::exp(-cot2));
  // The search starts at Jakob's fit of the inverse CDF ("An improved
  // visible normal sampling routine for the Beckmann distribution", 2014),
  // a step or two from the root, not at the middle of the bracket.
  const float theta = std::atan2(sin_theta, cos_theta);
  const float fit = 1.0f + theta * (-0.876f + theta * (0.4265f - 0.0594f * theta));
  float b = high - (1.0f + high) * std::pow(1.0f - u0, fit);
  for (int step = 0; step < 32; ++step) {
    const float x = ErfInv(b);
    const float value = normalisation * (1.0f + b + inv_sqrt_pi * tan_theta * std::exp(-x * x)) - u0;
    if (std::abs(value) < 1e-6f) break;
    (value > 0 ? high : low) = b;
    const float derivative = normalisation * (1.0f - x * tan_theta);
    const float next = derivative > 0 ? b - value / derivative : 0.5f * (low + high);
    b = next > low && next < high ? next : 0.5f * (low + high);
  }
  return ErfInv(b);
}

inline float SampleBeckmannSlopeY(float u1) { return ErfInv(2.0f * u1 - 1.0f); }

// wi stretched to Beckmann's unit roughness, and the normal of the unit
// slope (x11, y11) sampled there, rotated and stretched back.
inline Vec3 StretchToUnitRoughness(Vec3 wi, const Roughness& r) {
  return Normalize(Vec3(r.alpha_x * wi.x, r.alpha_y * wi.y, wi.z));
}
inline Vec3 BeckmannNormalOfSlope(Vec3 stretched, const Roughness& r, float x11, float y11) {
  const float planar = std::sqrt(stretched.x * stretched.x + stretched.y * stretched.y);
  const float cos_phi = planar > 0 ? stretched.x / planar : 1.0f, sin_phi = planar > 0 ? stretched.y / planar : 0.0f;
  const float x = (cos_phi * x11 - sin_phi * y11) * r.alpha_x;
  const float y = (sin_phi * x11 + cos_phi * y11) * r.alpha_y;
  return Normalize(Vec3(-x, -y, 1.0f));
}

// A visible normal of the distribution seen from wi (wi.z > 0), with
// density VisibleNormalPdf: GGX by warps.h, Beckmann by stretching wi to
// unit roughness, sampling a slope there, and stretching back (Heitz &
// d'Eon 2014).
inline Vec3 SampleVisibleNormal(Vec3 wi, const Roughness& r, float u0, float u1) {
  if (r.distribution == Distribution::kGgx) return SampleGgxVisibleNormal(wi, r.alpha_x, r.alpha_y, u0, u1);
  const Vec3 stretched = StretchToUnitRoughness(wi, r);
  return BeckmannNormalOfSlope(stretched, r, SampleBeckmannSlopeX(stretched.z, u0), SampleBeckmannSlopeY(u1));
}

// Calls visit(m) for the visible normals SampleVisibleNormal gives at the
// midpoints of a strata × strata grid of (u0, u1), for integrals over
// them. Beckmann's slopes are separable, x by u0 and y by u1: each of its
// 2·strata slope searches is made once, not once per cell.
template <typename Visit>
void ForEachVisibleNormalOnGrid(Vec3 wi, const Roughness& r, int strata, Visit&& visit) {
  const auto at = [strata](int i) { return (float(i) + 0.5f) / float(strata); };
  if (r.distribution == Distribution::kGgx) {
    for (int i = 0; i < strata; ++i)
      for (int j = 0; j < strata; ++j) visit(SampleVisibleNormal(wi, r, at(i), at(j)));
    return;
  }
  const Vec3 stretched = StretchToUnitRoughness(wi, r);
  std::vector<float> y11(static_cast<size_t>(strata));
  for (int j = 0; j < strata; ++j) y11[size_t(j)] = SampleBeckmannSlopeY(at(j));
  for (int i = 0; i < strata; ++i) {
    const float x11 = SampleBeckmannSlopeX(stretched.z, at(i));
    for (int j = 0; j < strata; ++j) visit(BeckmannNormalOfSlope(stretched, r, x11, y11[size_t(j)]));
  }
}

// The density of visible normals, G1(wi)·max(0, wi·m)·D(m) / cos θi.
inline float VisibleNormalPdf(Vec3 wi, Vec3 m, const Roughness& r) {
  const float cos_wi_m = Dot(wi, m);
  if (!(cos_wi_m > 0) || !(wi.z > 0)) return 0.0f;
  return SmithG1(wi, r) * cos_wi_m * Ndf(m, r) / wi.z;
}

// --- Fresnel factors -------------------------------------------------------

// Fresnel reflectance of unpolarised light at the surface of a conductor
// of complex index η + iκ relative to the outside medium, at incidence
// cos θi (clamped to [0, 1]): the exact formula of a dielectric with a
// complex index (Born & Wolf §14.2). κ = 0 gives FresnelDielectric; η = 0,
// κ = 1 gives 1 at every angle (Mitsuba's perfect mirror).
inline float FresnelConductor(float cos_i, float eta, float k) {
  // The complex-index Fresnel equations in real arithmetic: with
  // a² + b² = |n² − sin²θ| and a = Re √(n² − sin²θ) (n = eta + i·k),
  //   R_s = (a² + b² + cos² − 2a·cos) / (a² + b² + cos² + 2a·cos),
  //   R_p = R_s · (cos²·(a² + b²) + sin⁴ − 2a·cos·sin²) / (… + 2a·cos·sin²).
  // The same values as complex arithmetic gives, without its slow library
  // division (__divsc3).
  cos_i = std::clamp(cos_i, 0.0f, 1.0f);
  const float cos2 = cos_i * cos_i, sin2 = 1.0f - cos2;
  const float eta2 = eta * eta, k2 = k * k;
  const float t0 = eta2 - k2 - sin2;
  const float a2_plus_b2 = std::sqrt(t0 * t0 + 4.0f * eta2 * k2);
  const float a = std::sqrt(std::max(0.0f, 0.5f * (a2_plus_b2 + t0)));
  const float t1 = a2_plus_b2 + cos2, t2 = 2.0f * cos_i * a;
  const float t3 = cos2 * a2_plus_b2 + sin2 * sin2, t4 = t2 * sin2;
  // A vanishing denominator is grazing incidence on n = 1: all reflected.
  const float r_s = t1 + t2 > 0 ? (t1 - t2) / (t1 + t2) : 1.0f;
  const float r_p = t3 + t4 > 0 ? r_s * (t3 - t4) / (t3 + t4) : r_s;
  return std::clamp(0.5f * (r_s + r_p), 0.0f, 1.0f);
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

// The directional albedo of an isotropic rough dielectric interface's
// reflection, ∫ F(wi·m) D(m) G2 / (4 cos θi cos θo) cos θo dωo at incidence
// cos θi from the side where the relative index is eta: the mean of
// F · G2 / G1(wi) over visible normals, on a strata × strata grid of
// their sampling (deterministic). Normals that reflect below the horizon
// contribute nothing.
inline float RoughDielectricReflectance(float cos_theta, const Roughness& r, float eta, int strata = 64) {
  cos_theta = std::clamp(cos_theta, 1e-4f, 1.0f);
  const Vec3 wi(SinFromCos(cos_theta), 0.0f, cos_theta);
  const float g1 = SmithG1(wi, r);
  double sum = 0;
  ForEachVisibleNormalOnGrid(wi, r, strata, [&](Vec3 m) {
    const Vec3 wo = ReflectAbout(wi, m);
    if (wo.z > 0) sum += FresnelDielectric(Dot(wi, m), eta) * SmithG2(wi, wo, r) / g1;
  });
  return float(sum / (double(strata) * strata));
}

}  // namespace yarf::microfacet
