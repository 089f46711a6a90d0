// The checks every medium makes of its coefficient properties, and the
// parameters they read.
#pragma once

#include <string>

#include "yarf/error.h"
#include "yarf/geometry.h"
#include "yarf/parameters.h"
#include "yarf/properties.h"

namespace yarf {

// An rgb (or float) property that must be finite and non-negative; 0 when
// absent unless `fallback` says otherwise.
inline Vec3 NonNegativeColor(const Properties& props, const char* key, Vec3 fallback = Vec3(0, 0, 0)) {
  const Vec3 c = props.Color(key, fallback);
  if (!(c.x >= 0 && c.y >= 0 && c.z >= 0 && MaxComponent(c) < kInfinity))
    throw Error(std::string("property '") + key + "' must be finite and non-negative");
  return c;
}

// The property `scale` (default 1), which multiplies σ_a and σ_s.
inline float Scale(const Properties& props) {
  const float scale = float(props.Float("scale", 1));
  if (!(scale >= 0 && scale < kInfinity)) throw Error("property 'scale' must be finite and non-negative");
  return scale;
}

inline Parameter ScaleParameter() {
  return Parameter::Float("scale").Default(1.0).Min(0).Doc("multiplies sigma_a and sigma_s");
}

}  // namespace yarf
