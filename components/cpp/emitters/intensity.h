// The power parameter every emitter checks the same way.
#pragma once

#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "yarf/parameters.h"
#include "yarf/properties.h"
#include "yarf/texture.h"

namespace yarf {

// The declaration of a property RequiredIntensity reads: an rgb or a
// float, every channel >= 0; `doc` says what it is and its unit.
inline Parameter IntensityParameter(const std::string& name, std::string doc) {
  return Parameter::Rgb(name).Min(0).Doc(std::move(doc));
}

// The declaration of one RequiredTexturedIntensity reads: a texture too.
inline Parameter TexturedIntensityParameter(const std::string& name, std::string doc) {
  return Parameter::RgbTexture(name).Min(0).Doc(std::move(doc));
}

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
