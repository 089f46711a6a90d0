// pbrt-v4's named measured media (its `preset` of the homogeneous medium):
// scattering and absorption measured in RGB by Jensen et al., "A Practical
// Model for Subsurface Light Transport" (SIGGRAPH 2001), and Narasimhan et
// al., "Acquiring Scattering Properties of Participating Media by
// Dilution" (SIGGRAPH 2006).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "importers/spectrum.h"

namespace yarf::importers {

struct MeasuredMedium {
  const char* name;
  // The reduced scattering coefficient σ's, which pbrt-v4 uses as σ_s,
  // and the absorption coefficient σ_a, both per millimetre, linear sRGB.
  Rgb sigma_prime_s, sigma_a;
};

// The medium pbrt-v4 names so (its spelling, e.g. "Skin1", "Regular
// Milk"), or nullopt.
std::optional<MeasuredMedium> PbrtMeasuredMedium(const std::string& name);
// Every name, for suggestions.
std::vector<std::string> PbrtMeasuredMediumNames();

}  // namespace yarf::importers
