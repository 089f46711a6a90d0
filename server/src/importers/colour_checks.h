// Colours from scene files brought into the ranges yarf's components
// accept, saying so when a value had to change.
#pragma once

#include <algorithm>
#include <functional>
#include <string>

#include "importers/spectrum.h"

namespace yarf::importers {

// Clamps each channel into [lo, hi]; calls `warn` when anything changed.
inline Rgb ClampColour(Rgb c, double lo, double hi, const std::function<void()>& warn) {
  const Rgb clamped{std::clamp(c.r, lo, hi), std::clamp(c.g, lo, hi), std::clamp(c.b, lo, hi)};
  if (clamped.r != c.r || clamped.g != c.g || clamped.b != c.b) warn();
  return clamped;
}

}  // namespace yarf::importers
