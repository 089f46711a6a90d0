// Named metals for the conductor models (conductor.cc, roughconductor.cc):
// the reading of the 'material', 'eta' and 'k' properties Mitsuba's
// conductors share. The metals are yarf/support/named_metals.h's: every one
// Mitsuba 3 names, in the RGB Mitsuba's RGB variants convert its spectra
// to. An RGB renderer can only approximate a spectral one.
#pragma once

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "yarf/error.h"
#include "yarf/support/named_metals.h"
#include "yarf/parameters.h"
#include "yarf/properties.h"
#include "yarf/texture.h"
#include "yarf/vecmath.h"

namespace yarf::metals {

// Mitsuba's "none": η = 0, κ = 1, whose Fresnel reflectance is 1 at every
// angle (a perfect mirror).
inline constexpr ComplexIor kPerfectMirror = {{0.0f, 0.0f, 0.0f}, {1.0f, 1.0f, 1.0f}};

// The names 'material' accepts: its parameter's choices.
inline std::vector<std::string> Names() {
  std::vector<std::string> names = {"none"};
  for (const NamedMetal& metal : kMetals) names.emplace_back(metal.name);
  return names;
}

// The same, for messages.
inline std::string KnownNames() {
  std::string out;
  for (const std::string& name : Names()) out += (out.empty() ? "" : ", ") + name;
  return out;
}

// A conductor's index at the points of a surface call: constant, or
// textured per channel.
class TexturedIor {
 public:
  struct Points {
    PointValues<Vec3> eta, k;
  };
  TexturedIor(TexturedValue eta, TexturedValue k) : eta_(std::move(eta)), k_(std::move(k)) {}
  Points At(const SurfacePoints& at) const { return {eta_.At(at), k_.At(at)}; }

 private:
  TexturedValue eta_, k_;
};

// The complex index a conductor's properties give: 'material' names a
// metal (default "none"), or 'eta' and 'k' (rgb, float or a texture;
// defaults 0 and 1, a perfect mirror) give it directly; the two ways
// exclude each other, as in Mitsuba. Constant η and κ must be ≥ 0 and
// not both 0 in any channel; textured ones are clamped to [0, 10⁴] (both
// 0 reflects everything, as κ → 0 with η → 0 does).
inline TexturedIor ReadConductorIor(const Properties& props) {
  const std::string material = props.String("material", "none");
  if (material != "none") {
    if (props.Has("eta") || props.Has("k"))
      throw Error("properties 'material' and 'eta'/'k' exclude each other: name a metal or "
                  "give its index");
    for (const NamedMetal& metal : kMetals)
      if (material == metal.name) return {TexturedValue(metal.ior.eta), TexturedValue(metal.ior.k)};
    throw Error("property 'material': unknown metal \"" + material + "\" (known: " +
                KnownNames() + ")");
  }
  constexpr float kLargest = 1e4f;
  TexturedValue eta = TexturedValue::Color(props, "eta", kPerfectMirror.eta, /*unit=*/false);
  TexturedValue k = TexturedValue::Color(props, "k", kPerfectMirror.k, /*unit=*/false);
  for (int c = 0; c < 3; ++c) {
    if (eta.IsConstant() && !(eta.Constant()[c] >= 0.0f && std::isfinite(eta.Constant()[c])))
      throw Error("property 'eta' must be finite and ≥ 0 in every channel");
    if (k.IsConstant() && !(k.Constant()[c] >= 0.0f && std::isfinite(k.Constant()[c])))
      throw Error("property 'k' must be finite and ≥ 0 in every channel");
    if (eta.IsConstant() && k.IsConstant() && eta.Constant()[c] == 0.0f && k.Constant()[c] == 0.0f)
      throw Error("properties 'eta' and 'k' are both 0 in a channel: no such conductor");
  }
  return {eta.Clamped(0, kLargest), k.Clamped(0, kLargest)};
}

// The parameters ReadConductorIor reads. material "none" behaves as when
// it is left out; eta and k have no declared default: they exclude a
// named metal.
inline std::vector<Parameter> ConductorIorParameters() {
  return {
      Parameter::String("material").Default("none").Choices(Names()).Doc("a named metal, or none: eta and k"),
      Parameter::RgbTexture("eta").Min(0).Doc("real part η of the complex index, with material none (default 0)"),
      Parameter::RgbTexture("k").Min(0).Doc("imaginary part κ of the complex index, with material none (default 1)"),
  };
}

}  // namespace yarf::metals
