// Property checks several surface models share (bsdfs/*.cc): indices of
// refraction, and two colours whose sum must not create energy. Each
// throws an Error that names the property, so a scene's mistake points at
// its key; a texture, which cannot be checked before it is looked up, is
// brought into range at each point instead. (Roughness is read in
// microfacet.h, a conductor's complex index in metals.h.) Each reader's
// parameters are declared beside it; JoinParameters makes a class's
// schema of them.
#pragma once

#include <cmath>
#include <initializer_list>
#include <string>
#include <vector>

#include "yarf/error.h"
#include "yarf/parameters.h"
#include "yarf/properties.h"
#include "yarf/texture.h"
#include "yarf/vecmath.h"

namespace yarf {

// One schema of the parts several readers declare, in order.
inline std::vector<Parameter> JoinParameters(std::initializer_list<std::vector<Parameter>> parts) {
  std::vector<Parameter> out;
  for (const std::vector<Parameter>& part : parts) out.insert(out.end(), part.begin(), part.end());
  return out;
}

inline float RequireIndex(double ior, const std::string& property) {
  if (!(ior > 0.0 && std::isfinite(ior)))
    throw Error("property '" + property + "' must be a finite number > 0");
  return float(ior);
}

// int_ior / ext_ior, the relative index of the inside (-z) over the
// outside (+z), from the properties with the given defaults.
inline float ReadRelativeIndex(const Properties& props, double int_ior, double ext_ior) {
  return RequireIndex(props.Float("int_ior", int_ior), "int_ior") /
         RequireIndex(props.Float("ext_ior", ext_ior), "ext_ior");
}

// The parameters ReadRelativeIndex reads, with the same defaults.
inline std::vector<Parameter> RelativeIndexParameters(double int_ior, double ext_ior) {
  return {
      Parameter::Float("int_ior").Default(int_ior).Min(0).Doc("index of refraction inside (the -z side), > 0"),
      Parameter::Float("ext_ior").Default(ext_ior).Min(0).Doc("index of refraction outside (the +z side), > 0"),
  };
}

// Throws unless a + b ≤ 1 in every channel: two lobes' colours (named by
// their properties) that together would reflect more than arrives.
inline void RequireEnergyConserving(Vec3 a, Vec3 b, const std::string& name_a,
                                    const std::string& name_b) {
  static constexpr const char* kChannel[] = {"red", "green", "blue"};
  for (int c = 0; c < 3; ++c)
    if (a[c] + b[c] > 1.0f)
      throw Error("properties '" + name_a + "' + '" + name_b + "' exceed 1 in the " +
                  kChannel[c] + " channel: the material would create energy");
}

// The same for two properties that may be textures: checked here when
// both are constants, at each point by ConserveEnergy otherwise.
inline void RequireEnergyConserving(const TexturedValue& a, const TexturedValue& b,
                                    const std::string& name_a, const std::string& name_b) {
  if (a.IsConstant() && b.IsConstant())
    RequireEnergyConserving(a.Constant(), b.Constant(), name_a, name_b);
}

// Scales a and b down together in each channel where their sum exceeds 1
// (textured lobes' colours at one point); colours that passed
// RequireEnergyConserving are left exactly as they are.
inline void ConserveEnergy(Vec3& a, Vec3& b) {
  float out_a[3], out_b[3];
  for (int c = 0; c < 3; ++c) {
    const float sum = a[c] + b[c];
    out_a[c] = sum > 1.0f ? a[c] / sum : a[c];
    out_b[c] = sum > 1.0f ? b[c] / sum : b[c];
  }
  a = Vec3::Load(out_a);
  b = Vec3::Load(out_b);
}

}  // namespace yarf
