// Filling yarf Properties and ComponentSpecs.
#pragma once

#include <cstdint>
#include <string>

#include "importers/spectrum.h"
#include "yarf/v1/scene.pb.h"

namespace yarf::importers {

inline v1::Property& Slot(v1::Properties& p, const std::string& name) { return (*p.mutable_values())[name]; }

inline void SetFloat(v1::Properties& p, const std::string& name, double v) { Slot(p, name).set_float_value(v); }
inline void SetInt(v1::Properties& p, const std::string& name, int64_t v) { Slot(p, name).set_int_value(v); }
inline void SetBool(v1::Properties& p, const std::string& name, bool v) { Slot(p, name).set_bool_value(v); }
inline void SetString(v1::Properties& p, const std::string& name, const std::string& v) {
  Slot(p, name).set_string_value(v);
}
inline void SetRgb(v1::Properties& p, const std::string& name, const Rgb& c) {
  v1::Rgb& rgb = *Slot(p, name).mutable_rgb_value();
  rgb.set_r(c.r), rgb.set_g(c.g), rgb.set_b(c.b);
}

inline v1::ComponentSpec Spec(const std::string& class_name, v1::Properties properties = {}) {
  v1::ComponentSpec spec;
  spec.set_class_name(class_name);
  if (!properties.values().empty()) *spec.mutable_properties() = std::move(properties);
  return spec;
}

}  // namespace yarf::importers
