// The power parameter every emitter checks the same way.
#pragma once

#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "yarf/properties.h"
#include "yarf/texture.h"

namespace yarf {

// A required rgb (or float) property, finite and non-negative.
inline Vec3 RequiredIntensity(const Properties& props, const std::string& name) {
  const Vec3 value = props.Color(name);
  for (int c = 0; c < 3; ++c)
    if (!(value[c] >= 0.0f && std::isfinite(value[c])))
      throw Error("property '" + name + "' must be finite and non-negative in every channel");
  return value;
}

// The same property where it may also be a texture (an area light's
// radiance): a texture's values are clamped to [0, float max] where they
// are looked up.
inline TexturedValue RequiredTexturedIntensity(const Properties& props, const std::string& name) {
  if (auto texture = props.TextureOf(name))
    return TexturedValue(std::move(texture)).Clamped(0.0f, std::numeric_limits<float>::max());
  return TexturedValue(RequiredIntensity(props, name));
}

}  // namespace yarf
