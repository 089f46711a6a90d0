// What the two Disney models (principled.cc, principledthin.cc) share, as
// Mitsuba 3 writes them: their base colour and parameters in [0, high]
// (numbers or textures), read at a call's points, and sampling rates, each
// with its declared parameter; Schlick's Fresnel approximation, the hue
// of the base colour, Disney's roughness remapping, and the diffuse base
// with its retro-reflection, fake subsurface and sheen.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "microfacet.h"
#include "yarf/error.h"
#include "yarf/parameters.h"
#include "yarf/properties.h"
#include "yarf/surface_points.h"
#include "yarf/texture.h"
#include "yarf/vecmath.h"

namespace yarf::principled {

// --- Parameters ------------------------------------------------------------

// A weight parameter: its property, default, what it does, and range
// [0, high].
struct ParameterInfo {
  const char* name;
  float fallback;
  const char* doc;
  float high = 1.0f;
};

// The parameter ReadWeight reads.
inline Parameter WeightParameter(const ParameterInfo& info) {
  return Parameter::FloatTexture(info.name).Default(double(info.fallback)).Range(0, info.high).Doc(info.doc);
}

// The base colour c both models read: a reflectance, clamped into [0, 1]
// where it is a texture.
inline TexturedValue ReadBaseColor(const Properties& props) {
  return TexturedValue::Color(props, "base_color", Vec3(0.5f, 0.5f, 0.5f), /*unit=*/true);
}

inline Parameter BaseColorParameter() {
  return Parameter::RgbTexture("base_color").Default(0.5).Range(0, 1).Doc("c, the base colour, per channel");
}

// A weight as a number (checked against its range) or a texture (clamped
// into it at each point).
inline TexturedValue ReadWeight(const Properties& props, const ParameterInfo& info) {
  if (auto texture = props.TextureOf(info.name)) return TexturedValue(std::move(texture)).Clamped(0.0f, info.high);
  const double value = props.Float(info.name, info.fallback);
  if (!(value >= 0.0 && value <= info.high)) {
    std::ostringstream message;
    message << "property '" << info.name << "' must be a number in [0, " << info.high << "]";
    throw Error(message.str());
  }
  return TexturedValue(float(value));
}

// The base colour and the N weights at a call's points; row k is read as
// one Material(base, weights), each model's struct of what it derives
// from them.
template <typename Material, size_t N>
class PointParameters {
 public:
  PointParameters(const TexturedValue& base, const std::array<TexturedValue, N>& values, const SurfacePoints& at)
      : base_(base.At(at)) {
    for (const TexturedValue& value : values) values_.push_back(value.FloatsAt(at));
  }

  Material operator[](size_t k) const {
    std::array<float, N> values;
    for (size_t i = 0; i < N; ++i) values[i] = values_[i][k];
    return Material(base_[k], values);
  }

 private:
  PointValues<Vec3> base_;
  std::vector<PointValues<float>> values_;
};

// The odds Sample gives a lobe, relative to the others: Mitsuba's
// "*_sampling_rate" properties.
inline float ReadSamplingRate(const Properties& props, const std::string& name) {
  const double rate = props.Float(name, 1.0);
  if (!(rate >= 0.0 && std::isfinite(rate))) throw Error("property '" + name + "' must be a finite number ≥ 0");
  return float(rate);
}

inline Parameter SamplingRateParameter(const std::string& name) {
  return Parameter::Float(name).Default(1.0).Min(0).Doc("the odds Sample gives its lobe, relative to the others");
}

// --- Fresnel and colour ----------------------------------------------------

// Schlick's weight (1 - cos θ)⁵.
inline float SchlickWeight(float cos_theta) {
  const float m = std::clamp(1.0f - cos_theta, 0.0f, 1.0f);
  return (m * m) * (m * m) * m;
}

// Schlick's Fresnel factor of normal reflectance r0 at incidence cos_i on
// a facet of relative index eta; from the dense side, at the refracted
// angle (so that it follows total internal reflection), as Mitsuba.
inline Vec3 Schlick(Vec3 r0, float cos_i, float eta) {
  const float eta_it = cos_i >= 0 ? eta : 1.0f / eta;
  float weight = SchlickWeight(std::abs(cos_i));
  if (!(eta_it > 1.0f)) {
    const float cos2_t = 1.0f - (1.0f - cos_i * cos_i) / (eta_it * eta_it);
    weight = SchlickWeight(std::sqrt(std::max(0.0f, cos2_t)));
  }
  return r0 + (Vec3(1.0f, 1.0f, 1.0f) - r0) * weight;
}

// The normal reflectance ((η - 1) / (η + 1))² of a dielectric.
inline float NormalReflectance(float eta) { return (eta - 1.0f) * (eta - 1.0f) / ((eta + 1.0f) * (eta + 1.0f)); }

// c / lum(c), the hue of a colour (white when it is black).
inline Vec3 Tint(Vec3 c) {
  const float lum = Luminance(c);
  return lum > 0 ? c / lum : Vec3(1.0f, 1.0f, 1.0f);
}

inline Vec3 Lerp(Vec3 a, Vec3 b, float t) { return a * (1.0f - t) + b * t; }

// --- Roughness -------------------------------------------------------------

// GGX of Disney's α = ρ², stretched along x by the anisotropy; Mitsuba's
// floor of 0.001.
inline microfacet::Roughness DisneyRoughness(float roughness, float anisotropic) {
  const float r2 = roughness * roughness;
  const float aspect = std::sqrt(1.0f - 0.9f * anisotropic);
  return {std::max(0.001f, r2 / aspect), std::max(0.001f, r2 * aspect), microfacet::Distribution::kGgx};
}

// --- The diffuse base --------------------------------------------------------

// Burley's diffuse shape, f·π/base_color: (1 - F_i/2)(1 - F_o/2) plus the
// retro-reflection of roughness ρ, blended toward Hanrahan–Krueger's fake
// subsurface term by flatness. cos_d is cos θd, between h and wo.
inline float DiffuseShape(float roughness, float flatness, float cos_i, float cos_o, float cos_d) {
  const float fi = SchlickWeight(cos_i), fo = SchlickWeight(cos_o);
  const float retro_reach = 2.0f * roughness * cos_d * cos_d;
  float shape = (1.0f - 0.5f * fi) * (1.0f - 0.5f * fo) + retro_reach * (fo + fi + fo * fi * (retro_reach - 1.0f));
  if (flatness > 0) {
    // The subsurface approximation, flattened by roughness.
    const float f90 = 0.5f * retro_reach;
    const float fss = (1.0f + (f90 - 1.0f) * fo) * (1.0f + (f90 - 1.0f) * fi);
    const float subsurface = 1.25f * (fss * (1.0f / (cos_o + cos_i) - 0.5f) + 0.5f);
    shape += (subsurface - shape) * flatness;
  }
  return shape;
}

// The sheen at full weight: (1 - cos θd)⁵ in white tinted toward the hue
// of the base colour by sheen_tint. (No 1/π, as in Mitsuba.)
inline Vec3 Sheen(Vec3 base, float sheen_tint, float cos_d) {
  return Lerp(Vec3(1.0f, 1.0f, 1.0f), Tint(base), sheen_tint) * SchlickWeight(std::abs(cos_d));
}

}  // namespace yarf::principled
