// Property checks several surface models share (bsdfs/*.cc): indices of
// refraction, and two colours whose sum must not create energy. Each
// throws an Error that names the property, so a scene's mistake points at
// its key. (Roughness is read in microfacet.h, a conductor's complex
// index in metals.h.)
#pragma once

#include <cmath>
#include <string>

#include "yarf/error.h"
#include "yarf/properties.h"
#include "yarf/vecmath.h"

namespace yarf {

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

}  // namespace yarf
