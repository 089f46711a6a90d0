// The power parameter every emitter checks the same way.
#pragma once

#include <cmath>
#include <string>

#include "yarf/properties.h"

namespace yarf {

// A required rgb (or float) property, finite and non-negative.
inline Vec3 RequiredIntensity(const Properties& props, const std::string& name) {
  const Vec3 value = props.Color(name);
  for (int c = 0; c < 3; ++c)
    if (!(value[c] >= 0.0f && std::isfinite(value[c])))
      throw Error("property '" + name + "' must be finite and non-negative in every channel");
  return value;
}

}  // namespace yarf
